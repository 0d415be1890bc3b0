"""The integrators section: stability limits (`pd stability`), accuracy against force evaluations
of the dynamic integrators and time to steady state of the quasi-static ones (`pd compare`)."""
from __future__ import annotations

from typing import Callable

from . import records as R
from .fmt import esc, fnum, pct
from .markup import failed_box, num_td, table
from .page import Page, plt



def section(page: Page) -> str:
    parts = ['<section id="integrators"><h2>Integrators</h2>', "<h3>Stability limit</h3>",
             '<p class="note"><code>pd stability SCENE --json</code>: the largest fixed Δt that '
             "stays bounded, found by bisection, beside Miranda's eq. 31 bound and two sharp "
             "predictions: β/ω<sub>max</sub> (β = the method's stability interval on the imaginary "
             "axis, 2 for Verlet; ω<sub>max</sub> by Lanczos on the linearised operator), the "
             "limit of infinitely long runs, and the finite-horizon prediction of the bounded "
             "run itself: the perturbation's energy, split over the modes by a Lanczos (Gauss "
             "quadrature) spectral measure, grows by |R(iωΔt)|<sup>2N</sup> per mode in N steps, "
             "and the run counts as unstable once it has grown 1000-fold. Tables whose |R(iy)| "
             "exceeds 1 only marginally (Dormand–Prince past β, and Heun–Euler, Cash–Karp, "
             "Fehlberg with β = 0) have a finite measured limit that only the second prediction "
             "describes; it tends to β/ω<sub>max</sub> as N grows. The default report measures "
             "the bar with Verlet and one table per order (Heun–Euler, Bogacki–Shampine, RK4, "
             "Dormand–Prince); <code>--full</code> adds the other tables and two more scenes.</p>"]
    rec = page.rec.get("stability")
    if not R.ok(rec):
        parts.append(failed_box(rec, "stability limits"))
    else:
        rows = []
        for r in rec["result"]["rows"]:
            rows.append([esc(r.get("case")), esc(r.get("integrator")), num_td(fnum(r.get("interval"))),
                         num_td(fnum(r.get("measured_dt"))), num_td(fnum(r.get("eq31_dt"))),
                         num_td(fnum(r.get("sharp_dt")) if r.get("sharp_dt") else "– (β = 0)"),
                         num_td(fnum(r.get("measured_over_eq31"), 3)),
                         num_td(fnum(r.get("measured_over_sharp"), 3) if r.get("sharp_dt") else "–"),
                         num_td(fnum(r.get("sharp_finite_horizon_dt"))),
                         num_td(fnum(r.get("measured_over_sharp_finite_horizon"), 3)),
                         num_td(fnum(r.get("runs"))), num_td(fnum(r.get("wall_seconds"), 3))])
        parts.append(table(["case", "integrator", "β", "measured Δt (s)", "eq. 31 Δt (s)",
                            "sharp β/ω_max (s)", "measured / eq. 31", "measured / sharp",
                            "sharp, finite horizon (s)", "measured / sharp (fin.)", "runs",
                            "wall (s)"], rows, 'id="stability-table"'))
    parts.append("<h3>Accuracy vs force evaluations (bar vibration)</h3>")
    parts.append(_comparison(page, "compare:dynamic", "dynamic integrator comparison", dynamic_block))
    parts.append("<h3>Quasi-static: time to steady state (clamped beam)</h3>")
    parts.append(_comparison(page, "compare:quasistatic", "quasi-static integrator comparison",
                             quasistatic_block))
    parts.append("</section>")
    return "".join(parts)


def _comparison(page: Page, stage: str, what: str, block: Callable[[Page, list[dict]], str]) -> str:
    rec = page.rec.get(stage)
    return block(page, rec["result"]["rows"]) if R.ok(rec) else failed_box(rec, what)


def dynamic_block(page: Page, rows: list[dict]) -> str:
    series: dict[str, list[dict]] = {}
    for r in rows:
        series.setdefault(R.integrator_label(r), []).append(r)
    fig, ax = plt.subplots(figsize=(7.2, 4.6))
    markers = "osD^v<>pP*X"
    for i, (label, rs) in enumerate(sorted(series.items())):
        rs = sorted(rs, key=lambda r: r.get("force_evaluations", 0))
        xs = [r.get("force_evaluations", 0) for r in rs]
        ys = [max(abs(r.get("error", 0.0)), 1e-16) for r in rs]
        ax.loglog(xs, ys, "-" + markers[i % len(markers)], ms=5, lw=1, label=label)
    ax.set_xlabel("force evaluations")
    ax.set_ylabel("free-end RMS error / (εL)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("bar vibration: error vs cost", fontsize=10)
    img = page.savefig(fig, "integrators-dynamic.png")
    trows = []
    for r in rows:
        trows.append([esc(R.integrator_label(r)), num_td(fnum(r.get("dt"))), num_td(fnum(r.get("dt_over_eq31"), 3)),
                      num_td(fnum(r.get("error"))), num_td(fnum(r.get("error_vs_reference_pd"))),
                      num_td(fnum(r.get("force_evaluations"))), num_td(fnum(r.get("wall_seconds"), 3)),
                      esc(r.get("status", ""))])
    measure = rows[0].get("error_measure", "") if rows else ""
    length, end = (rows[0].get("bar_length"), rows[0].get("end_time")) if rows else (None, None)
    extent = (f" The bar is {length:g} m long and runs to t = {end:.4g} s (the default report's "
              "<code>pd compare dynamic --quick</code>: half the case's bar for one period; "
              "<code>--full</code>: the case itself, 1 m for 6.4 periods, and finer steps)."
              if length and end else "")
    return (f'<img src="{img}" alt="integrator accuracy vs cost">'
            f'<p class="note">error measure: {esc(measure)}; error vs the modal series includes '
            f"the PD model's own (spatial) error, which is the floor the curves reach.{extent}</p>" +
            table(["integrator", "Δt (s)", "Δt / eq. 31", "error vs modal series",
                   "error vs PD reference", "force evaluations", "wall (s)", "status"], trows))


def quasistatic_block(page: Page, rows: list[dict]) -> str:
    trows, labels, walls, fevals = [], [], [], []
    for r in rows:
        label = R.quasistatic_label(r)
        labels.append(label)
        walls.append(float(r.get("wall_seconds") or 0))
        fevals.append(float(r.get("force_evaluations") or 0))
        trows.append([esc(label), num_td(fnum(r.get("dt"))), num_td(fnum(r.get("steps"))),
                      num_td(fnum(r.get("force_evaluations"))), num_td(fnum(r.get("wall_seconds"), 3)),
                      num_td(fnum(r.get("midspan_deflection"))), num_td(pct(r.get("error"))),
                      num_td(fnum(r.get("residual"))), esc(r.get("status", ""))])
    fig, ax = plt.subplots(figsize=(7.2, 0.5 + 0.45 * max(len(labels), 1)))
    ax.barh(labels, walls, color="#4a78b5")
    for i, (w, f) in enumerate(zip(walls, fevals)):
        ax.text(w, i, f"  {w:.1f} s, {int(f)} evals", va="center", fontsize=8)
    ax.set_xlabel("wall time to steady state (s)")
    ax.invert_yaxis()
    ax.set_xlim(0, max(walls + [1]) * 1.45)
    spacing = next((r["spacing"] for r in rows if r.get("spacing")), None)
    at = f" at λ = {spacing:g} m" if spacing else ""
    ax.set_title(f"clamped beam{at}: time to steady state", fontsize=10)
    img = page.savefig(fig, "integrators-quasistatic.png")
    fastest = min(range(len(walls)), key=lambda i: walls[i]) if walls else None
    reading = ""
    if fastest is not None and rows:
        ok_rows = [i for i, r in enumerate(rows) if r.get("status") == "converged"]
        if ok_rows:
            fastest = min(ok_rows, key=lambda i: walls[i])
        ref = next((i for i, r in enumerate(rows) if r.get("integrator") == "damped-euler"), None)
        reading = f"Fastest to steady state: {labels[fastest]} ({walls[fastest]:.2g} s"
        if ref is not None and walls[fastest] > 0:
            reading += f", {walls[ref] / walls[fastest]:.2g}× faster than damped Euler"
        reading += ")."
    if spacing:
        reading += (f" Clamped beam at λ = {spacing:g} m (the default report's `pd compare quasistatic "
                    "--quick` takes twice the paper's spacing and one ARKode table, rk4; --full runs "
                    "the paper's spacing and adds Bogacki–Shampine and adaptive Dormand–Prince).")
    return (f'<img src="{img}" alt="time to steady state">' +
            (f'<p class="reading">{esc(reading)}</p>' if reading else "") +
            table(["integrator", "Δt (s)", "steps", "force evaluations", "wall (s)",
                   "midspan deflection (m)", "vs static", "residual", "status"], trows))
