"""The structures' sections: deflection lines (PD vs deal.II vs beam/plate theory, as Miranda et
al. 2019 plot them) and accuracy vs time (the sweeps of `pd verify --sweep`)."""
from __future__ import annotations

import math

from . import records as R
from . import theory as th
from .cases import in_listed_order
from .fmt import esc, fnum, pct, short
from .markup import failed_box, num_td, table
from .page import Page, plt


def deflections(page: Page) -> str:
    order = in_listed_order(page.cases, R.listed_cases(page.rec, page.meta))
    figures = [str(l.paper_figure) for c in order for l in page.cases[c].lines if l.paper_figure]
    parts = ['<section id="deflections"><h2>Deflection lines: PD vs deal.II vs theory</h2>',
             f'<p class="note">As Miranda et al. 2019 Figs. {", ".join(figures)}. PD values on the '
             "particle layers of the centre line (interpolated to the line through the body's "
             "centre), FE = deal.II Q2 finest mesh, theory = Euler–Bernoulli and Timoshenko "
             "closed forms (beams; parameters from the gold file's <code>theory</code>) and the "
             "Kirchhoff Rayleigh–Ritz point values (plate). Lower panels: (PD − FE) / max|FE| "
             "along the line.</p>"]
    fem = {r["result"]["problem"]: r["result"] for r in page.group("fem").values() if r.get("result")}
    for r in page.group("fem").values():
        if not R.ok(r):
            parts.append(failed_box(r, "FE reference check"))
    figs = []
    for case in order:
        rec = page.rec.get(f"verify:{case}")
        if not R.ok(rec):
            parts.append(failed_box(rec, f"verification case {case} (deflection lines)"))
            continue
        d = rec["result"]
        for line, ldata in (d.get("lines") or {}).items():
            figs.append(deflection_figure(page, case, line, ldata, d, fem.get(page.cases[case].fe_reference)))
    parts.append('<div class="figs">' + "".join(figs) + "</div></section>")
    return "".join(parts)


def deflection_figure(page: Page, case: str, line: str, ldata: dict, d: dict, fem: dict | None) -> str:
    described = page.cases[case].line(line)
    cols = ldata.get("columns", ["position", "pd", "fe"])
    rows = ldata.get("rows", [])
    ip, ipd, ife = cols.index("position"), cols.index("pd"), cols.index("fe")
    x = [r[ip] for r in rows]
    pdv = [r[ipd] * 1e3 for r in rows]
    fev = [r[ife] * 1e3 for r in rows]
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(6.4, 5.2), sharex=True,
                                  gridspec_kw={"height_ratios": [3, 1.3]})
    axis = described.along if described else "s"
    fe_src = "FE at PD layers"
    if fem and described and described.fe_csv in fem.get("lines", {}):
        fl = fem["lines"][described.fe_csv]
        ax.plot(fl[axis], [v * 1e3 for v in fl["deflection"]], "-", color="#1f5fbf", lw=2,
                label="deal.II (Q2, finest mesh)")
        fe_src = "deal.II line"
    else:
        ax.plot(x, fev, "-", color="#1f5fbf", lw=2, label="deal.II (at PD layers)")
    theory_obj = (fem or {}).get("theory") or {}
    note = ""
    if th.beam_kind(theory_obj):
        length = float(theory_obj["L"])
        xs = [length * i / 200 for i in range(201)]
        eb = [th.beam_deflection(theory_obj, xx)[0] * 1e3 for xx in xs]
        ti = [th.beam_deflection(theory_obj, xx)[1] * 1e3 for xx in xs]
        ax.plot(xs, eb, ":", color="#777", lw=1.5, label="Euler–Bernoulli")
        ax.plot(xs, ti, "--", color="#2a8a2a", lw=1.5, label="Timoshenko (κ = 5/6)")
        note = f" Closed forms reproduce the gold file's point values to {th.check_against_gold(theory_obj):.1e}."
    elif theory_obj.get("quantities"):
        points = {q.fe: q.point for q in page.cases[case].quantities}
        for qname, q in theory_obj["quantities"].items():
            if qname not in points or not isinstance(q, dict) or "kirchhoff" not in q:
                continue
            pos = described.position_of(points[qname]) if described else None
            if pos is None:
                continue
            ax.plot([pos], [q["kirchhoff"] * 1e3], "*", ms=13, color="#2a8a2a",
                    label=f"Kirchhoff {qname.replace('_', ' ')}")
    elif fem is None:
        note = " (FE reference stage missing: no theory curve.)"
    ax.plot(x, pdv, "o", ms=3.5, color="#c0392b", label="PD (libpd)")
    ax.invert_yaxis()
    ax.set_ylabel("deflection (mm, downward)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    s = d.get("settings", {})
    figure = f"Fig. {described.paper_figure}" if described and described.paper_figure else ""
    ax.set_title(f"{case} — {line} ({figure}); "
                 f"λ = {s.get('spacing', '?')} m, {s.get('stretch', '?')}", fontsize=10)
    fmax = max((abs(v) for v in fev), default=1.0) or 1.0
    ax2.plot(x, [100 * (p - f) / fmax for p, f in zip(pdv, fev)], "-o", ms=2.5, color="#c0392b")
    ax2.axhline(0, color="k", lw=0.6)
    ax2.set_ylabel("(PD−FE)/max|FE| (%)", fontsize=8)
    ax2.set_xlabel(f"{axis} (m)")
    ax2.grid(alpha=0.3)
    name = page.savefig(fig, f"deflection-{case}-{line}.png")
    err = ldata.get("max_difference_over_max_fe")
    return (f'<figure><img src="{name}" alt="{esc(case)} {esc(line)} deflection"><figcaption>'
            f"{esc(case)}, {esc(line)}: largest |PD − FE| / max|FE| = {pct(err)} "
            f"({len(rows)} PD layers; FE curve: {fe_src}).{esc(note)}</figcaption></figure>")


def accuracy_vs_time(page: Page) -> str:
    parts = ['<section id="accuracy"><h2>Accuracy vs time</h2>',
             '<p class="note">Each point is one run of <code>pd verify --sweep CASE</code>: the '
             "error against deal.II (largest over the case's quantities) against the wall time of "
             "the run, one marker series per knob. The Pareto front (no other run is both "
             "faster and more accurate) is the black line.</p>"]
    sweeps = page.group("sweep")
    if not sweeps:
        parts.append(failed_box(None, "accuracy-vs-time sweeps"))
    for name, rec in sweeps.items():
        case = name.split(":", 1)[1]
        parts.append(f"<h3>{esc(case)}</h3>")
        if not R.ok(rec):
            parts.append(failed_box(rec, f"sweep of {case}"))
            continue
        parts.append(sweep_block(page, case, rec["result"]["rows"], rec["result"]))
    parts.append("</section>")
    return "".join(parts)


def sweep_block(page: Page, case: str, rows: list[dict], result: dict | None = None) -> str:
    pts = R.sweep_points(rows)
    if not pts:
        return '<p class="fail">the sweep rows have no usable error_vs_fe / wall_seconds</p>'
    base = next((p for p in pts if p[2] == "baseline"), None)
    fig, ax = plt.subplots(figsize=(7.4, 4.8))
    markers = "osD^v<>pP*X"
    knobs = sorted({p[2] for p in pts if p[2] != "baseline"})
    for i, k in enumerate(knobs):
        sel = [p for p in pts if p[2] == k]
        if base is not None:
            sel = sel + [base]
        sel.sort(key=lambda p: p[0])
        line, = ax.loglog([p[0] for p in sel], [max(p[1], 1e-12) for p in sel],
                          markers[i % len(markers)], ls="-", lw=0.7, ms=6, alpha=0.85,
                          label=KNOB_LABEL.get(k, k))
        for p in sel:
            if p is base:
                continue
            ax.annotate(short(p[3]), (p[0], max(p[1], 1e-12)), fontsize=6.5, xytext=(3, 3),
                        textcoords="offset points", color=line.get_color())
    if base is not None:
        ax.loglog([base[0]], [max(base[1], 1e-12)], "*", ms=16, color="k", mfc="gold",
                  label="baseline (the scene)", zorder=5)
    front = R.pareto(pts)
    ax.loglog([p[0] for p in front], [max(p[1], 1e-12) for p in front], "-", color="k", lw=2.2,
              alpha=0.35, label="Pareto front", zorder=0)
    ax.set_xlabel("wall time of the run (s)")
    ax.set_ylabel("relative error vs FE (largest quantity)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax.set_title(f"{case}: error vs wall time", fontsize=10)
    img = page.savefig(fig, f"accuracy-{case}.png")
    readings = sweep_readings(pts)
    extra = (f'<p class="note">Error against λ with its observed order: <a href="#convergence-{esc(case)}">'
             f'Summary, convergence in λ</a>; the <code>corrections</code> rows are the old correction '
             f'pairs (<a href="#old-pairs-{esc(case)}">beside the default</a>).</p>')
    if result and result.get("reduced"):
        swept = ", ".join(c for c in in_listed_order(page.cases, R.listed_cases(page.rec, page.meta))
                          if page.cases[c].has_sweep)
        extra += ('<p class="note">Default report: a <b>reduced sweep</b> (the first value of each '
                  "knob list of the case file, besides the baseline); <code>--full</code> runs the "
                  f"complete sweeps of {esc(swept)}.</p>")
    trows = [[esc(KNOB_LABEL.get(p[2], p[2])), esc(short(p[3])), num_td(pct(p[1])), num_td(fnum(p[0], 3)),
              num_td(fnum(p[4].get("spacing"))), num_td(fnum(p[4].get("horizon_factor"), 3)),
              esc(p[4].get("stretch", "")), esc(f"{p[4].get('surface_correction', '')}/{p[4].get('volume_correction', '')}"),
              num_td(fnum(p[4].get("force_tolerance"))),
              num_td(fnum(p[4].get("particles"))), num_td(fnum(p[4].get("bonds"))),
              num_td(fnum(p[4].get("bond_updates"))), esc(p[4].get("status", "")),
              "★" if p in front else ""]
             for p in sorted(pts, key=lambda p: (p[2] != "baseline", p[2], p[0]))]
    return (f'<img src="{img}" alt="accuracy vs time {esc(case)}">' +
            "".join(f'<p class="reading">{esc(r)}</p>' for r in readings) + extra +
            table(["knob", "value", "error vs FE", "wall (s)", "λ (m)", "δ/λ", "stretch",
                   "corrections (surface/volume)", "force tol.", "particles", "bonds",
                   "bond updates", "status", "Pareto"], trows, 'class="sweep-table"'))


def _as_float(v: object) -> float | None:
    if isinstance(v, bool):
        return None
    try:
        return float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return None


# The sweep's `corrections` knob runs the pairs the scenes used before ghost + gradient.
KNOB_LABEL = {"corrections": "old correction pair"}

KNOB_FIELD = {"spacing": "spacing", "horizon_factor": "horizon_factor", "stretch": "stretch",
              "surface_correction": "surface_correction", "volume_correction": "volume_correction",
              "force_tolerance": "force_tolerance"}


def sweep_readings(pts: list[tuple]) -> list[str]:
    """One sentence per knob, computed from the rows (the baseline row joins every knob's series
    with its own setting of that knob)."""
    out = []
    base = next((p for p in pts if p[2] == "baseline"), None)
    by: dict[str, list[tuple]] = {}
    for p in pts:
        if p[2] != "baseline":
            by.setdefault(p[2], []).append(p)
    for knob, sel in sorted(by.items()):
        series = list(sel)
        if base is not None:
            bv = (R.corrections_of(base[4]) if knob == "corrections"
                  else base[4].get(KNOB_FIELD.get(knob, knob), "baseline"))
            series.append((base[0], base[1], knob, bv, base[4]))
        if len(series) < 2:
            continue
        nums = [_as_float(p[3]) for p in series]
        if knob in ("surface_correction", "volume_correction"):
            off = [p for p in series if str(p[3]).lower() in ("none", "off", "false")]
            on = [p for p in series if str(p[3]).lower() not in ("none", "off", "false")]
            if on and off:
                a, b = off[0], on[0]
                gain = a[1] / b[1] if b[1] > 0 else math.inf
                cost = b[0] / a[0] if a[0] > 0 else math.inf
                verdict = ("free accuracy" if gain > 1.05 and cost < 1.15 else
                           "buys accuracy at a cost" if gain > 1.05 else
                           "does not improve the error here")
                out.append(f"{knob.replace('_', ' ')} {short(b[3])}: error {pct(a[1])} without → "
                           f"{pct(b[1])} with ({gain:.2g}× less) for {cost:.2g}× the time — {verdict}.")
            continue
        if all(n is not None for n in nums):
            s2 = sorted(zip(nums, series), key=lambda t: t[0])
            if knob in ("spacing", "force_tolerance"):
                lo, hi = s2[-1][1], s2[0][1]     # coarsest/loosest -> finest/tightest
            else:
                lo, hi = s2[0][1], s2[-1][1]
            gain = lo[1] / hi[1] if hi[1] > 0 else math.inf
            cost = hi[0] / lo[0] if lo[0] > 0 else math.inf
            name = {"spacing": "refining λ", "horizon_factor": "a larger horizon factor δ/λ",
                    "force_tolerance": "a tighter force tolerance"}.get(knob, knob)
            if gain >= 1:
                out.append(f"{name} ({short(lo[3])} → {short(hi[3])}) buys {gain:.2g}× less error per "
                           f"{cost:.2g}× more time (error {pct(lo[1])} → {pct(hi[1])}).")
            else:
                out.append(f"{name} ({short(lo[3])} → {short(hi[3])}) makes the error {1 / gain:.2g}× LARGER "
                           f"for {cost:.2g}× the time (error {pct(lo[1])} → {pct(hi[1])}).")
            continue
        # categorical (stretch measure): each alternative against the baseline's choice
        if base is not None:
            ref = series[-1]
            for p in sel:
                gain = p[1] / ref[1] if ref[1] > 0 else math.inf
                cost = p[0] / ref[0] if ref[0] > 0 else math.inf
                out.append(f"{KNOB_LABEL.get(knob, knob)} {short(p[3])} instead of {short(ref[3])}: "
                           f"error {pct(ref[1])} → "
                           f"{pct(p[1])}, time ×{cost:.2g}.")
    best = min(pts, key=lambda p: p[1])
    out.append(f"Most accurate run: {best[2]} = {short(best[3])}, error {pct(best[1])} in {best[0]:.1f} s.")
    return out
