"""Griffith scaling of the virtual-fibre model (issue 17; Olsson, Ander & Williams 2021, Fig. 14):
σ_failure/σ_yield against √(δ_e/c) from our runs of `pd verify griffith-full` (or the CI variant
`griffith` when the full one did not run), with the least-squares line, its slope, intercept and
R², the c^(−1/2) check at fixed δ_e and the load–displacement histories the failure stresses are
read from."""
from __future__ import annotations

from . import records as R
from .fmt import esc, fnum, pct
from .markup import failed_box, num_td, table
from .page import Page, plt

CASES = ("griffith-full", "griffith")
# griffith-full's c^(−1/2) pair on a finer crack path, and that path on a larger disk: what
# still moves.
SENSITIVITY = (("griffith-full", "as run (path c/32)"),
               ("griffith-resolution", "finer crack path (c/64)"),
               ("griffith-boundary", "path c/64, larger disk (ξ_max 3.2)"))


def section(page: Page) -> str:
    parts = ['<section id="griffith"><h2>Griffith scaling with virtual fibres (Fig. 14)</h2>',
             '<p class="note">The elliptical disk of Olsson et al. §10 with a crack between its '
             "focal points, its boundary zone held at the eq. 116 field of a remote equibiaxial "
             "stress S that is raised in increments, each relaxed to equilibrium (ADR). The "
             "boundary stress σ_b is the boundary zone's summed reaction along the outward normal "
             "over the perimeter; σ_failure is the peak of σ_b before the crack runs. Griffith "
             "(eq. 117): σ_failure/σ_yield is linear in √(δ_e/c).</p>"]
    shown = None
    for case in CASES:
        rec = page.rec.get(f"verify:{case}")
        if R.ok(rec):
            shown = (case, rec["result"])
            break
    if shown is None:
        parts.append(failed_box(page.rec.get("verify:griffith"), "verification case griffith"))
        return "".join(parts) + "</section>"
    case, d = shown
    parts.append(f"<p>From <code>pd verify {esc(case)}</code>: "
                 f"{'<span class=pass>passed</span>' if d.get('passed') else '<span class=fail>FAILED</span>'}"
                 f" — {esc(d.get('gate'))}.</p>")
    parts.append(summary_table(d))
    parts.append(sensitivity_table(page))
    parts.append('<div class="figs">' + scaling_figure(page, case, d) + history_figure(page, case, d) +
                 "</div>")
    return "".join(parts) + "</section>"


def summary_table(d: dict) -> str:
    pdv = d.get("pd") or {}
    sc = d.get("crack_length_scaling") or {}
    sm = d.get("crack_length_scaling_half_delta") or {}
    res = d.get("resolution") or {}
    runs = d.get("sweep") or []
    particles = runs[0].get("particles") if runs else None
    rows = [["slope of σ_f/σ_y against √(δ_e/c)", num_td(fnum(pdv.get("slope")))],
            ["intercept", num_td(fnum(pdv.get("intercept")))],
            ["R² (gate ≥ 0.98)", num_td(fnum(pdv.get("r_squared")))],
            [f"σ_f(c/2) / σ_f(c) at δ_e = c/{_divisor(sc)} (√2 = 1.4142)", num_td(fnum(sc.get("ratio")))],
            ["its error against √2 (gate 5 %)",
             num_td(pct(sc.get("error")))],
            ["the same in the remote stress S (reported)", num_td(pct(sc.get("remote_ratio_error")))],
            [f"σ_f(c/2) / σ_f(c) at δ_e = c/{_divisor(sm)}, half the smallest (reported)",
             num_td(f"{fnum(sm.get('ratio'))} ({pct(sm.get('error'))})")],
            ["disk ξ_max; the crack's path at spacing (over c)",
             num_td(f"{fnum(res.get('xi_max'))}; {fnum(res.get('path_band_spacing_over_c'))}")],
            ["particles (paper: Table 1)", num_td(f"{fnum(particles)} ({fnum(res.get('paper_particles'))})")],
            ["load step ΔS/σ_y", num_td(fnum(res.get("load_step_over_yield")))],
            ["wall time", num_td(f"{fnum(d.get('wall_seconds'))} s")]]
    return table(["", ""], rows, 'id="griffith-table"')


def sensitivity_table(page: Page) -> str:
    """The gated pair of griffith-full beside the same pair on a larger disk and a finer path."""
    rows = []
    for case, what in SENSITIVITY:
        rec = page.rec.get(f"verify:{case}")
        if not R.ok(rec):
            continue
        d = rec["result"]
        res = d.get("resolution") or {}
        sc = d.get("crack_length_scaling") or {}
        rows.append([f"{esc(case)} ({what})", num_td(fnum(res.get("xi_max"))),
                     num_td(fnum(res.get("path_band_spacing_over_c"))),
                     num_td(fnum((sc.get("long_run") or _run_at(d, sc)).get("failure_over_yield"))),
                     num_td(fnum((sc.get("short_run") or {}).get("failure_over_yield"))),
                     num_td(f"{fnum(sc.get('ratio'))} ({pct(sc.get('error'))})")])
    if len(rows) < 2:
        return ""
    return table(["run", "ξ_max", "path spacing / c", "σ_f(c)/σ_y", "σ_f(c/2)/σ_y", "ratio (vs √2)"],
                 rows, 'id="griffith-sensitivity"')


def _run_at(d: dict, pair: dict) -> dict:
    """The sweep's run at the pair's δ_e (the pair reuses it rather than storing it again)."""
    for r in d.get("sweep") or []:
        if r.get("delta_over_c") == pair.get("long_delta_over_c"):
            return r
    return {}


def _divisor(pair: dict) -> str:
    v = pair.get("long_delta_over_c")
    return f"{1 / v:.0f}" if R.is_number(v) and v > 0 else "?"


def scaling_figure(page: Page, case: str, d: dict) -> str:
    runs = d.get("sweep") or []
    x = [r["sqrt_delta_over_c"] for r in runs if r.get("failed")]
    y = [r["failure_over_yield"] for r in runs if r.get("failed")]
    fig, ax = plt.subplots(figsize=(5.6, 4.2))
    ax.plot(x, y, "o", color="#1f5fbf", label="libpd (δ_e = c/750 … c/3250)" if case.endswith("full")
            else "libpd")
    pdv = d.get("pd") or {}
    if x and R.is_number(pdv.get("slope")):
        lo, hi = 0.0, max(x) * 1.05
        ax.plot([lo, hi], [pdv["intercept"] + pdv["slope"] * lo, pdv["intercept"] + pdv["slope"] * hi],
                "--", color="#555", label=f"least squares, R² = {pdv.get('r_squared', float('nan')):.4f}")
    for key, colour in (("crack_length_scaling", "#c0392b"), ("crack_length_scaling_half_delta", "#e67e22")):
        pair = d.get(key) or {}
        runs = [r for r in (pair.get("long_run"), pair.get("short_run")) if r and r.get("failed")]
        if runs:
            ax.plot([r["sqrt_delta_over_c"] for r in runs], [r["failure_over_yield"] for r in runs], "s",
                    color=colour, mfc="none" if key.endswith("half_delta") else colour,
                    label=f"c and c/2 at δ_e = c/{_divisor(pair)}")
    ax.set_xlabel("√(δ_e / c)")
    ax.set_ylabel("σ_failure / σ_yield")
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"Griffith scaling, virtual fibres ({case})", fontsize=10)
    name = page.savefig(fig, f"griffith-{case}-fig14.png")
    return f'<figure><img src="{name}" alt="Fig. 14 remade"><figcaption>Olsson et al. Fig. 14 remade ' \
           "from our runs.</figcaption></figure>"


def history_figure(page: Page, case: str, d: dict) -> str:
    fig, ax = plt.subplots(figsize=(5.6, 4.2))
    for r in d.get("sweep") or []:
        curve = r.get("curve") or []
        ax.plot([p["level"] for p in curve], [p["boundary_over_yield"] for p in curve], "-", lw=1,
                label=f"c/{1 / r['delta_over_c']:.0f}")
    ax.set_xlabel("S / σ_yield (eq. 116 boundary field)")
    ax.set_ylabel("σ_b / σ_yield (boundary reaction)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    name = page.savefig(fig, f"griffith-{case}-history.png")
    return f'<figure><img src="{name}" alt="load histories"><figcaption>The load histories the ' \
           "failure stresses are read from.</figcaption></figure>"
