"""What the structures' sweeps say about the default treatment: the error against deal.II as λ
shrinks (log-log, with the observed order) and the old correction pairs beside the default, each
read from the rows of `pd verify CASE-sweep` (knobs `spacing` and `corrections`)."""
from __future__ import annotations

import math

from . import records as R
from .cases import in_listed_order
from .fmt import esc, fnum, pct
from .markup import table
from .page import Page, plt

DEFAULT_PAIR = "ghost+gradient"


def fe_values(page: Page, case: str) -> tuple[dict[str, float], dict[str, float]]:
    """FE value and the FE solution's own relative error estimate per quantity of a case."""
    c = page.cases[case]
    fem = page.rec.get(f"fem:{c.fe_reference}")
    quantities = ((fem or {}).get("result") or {}).get("quantities") or {}
    values, estimates = {}, {}
    for q in c.quantities:
        fq = quantities.get(q.fe) or {}
        if R.is_number(fq.get("extrapolated")):
            values[q.name] = float(fq["extrapolated"])
        if R.is_number(fq.get("relative_error_estimate")):
            estimates[q.name] = float(fq["relative_error_estimate"])
    verify = page.rec.get(f"verify:{case}")
    if R.ok(verify):      # a run without the FE stage still has the values pd verify compared with
        for q, r in (verify["result"].get("reference") or {}).items():
            if isinstance(r, dict) and R.is_number(r.get("fe")):
                values.setdefault(q, float(r["fe"]))
                if R.is_number(r.get("fe_relative_error_estimate")):
                    estimates.setdefault(q, float(r["fe_relative_error_estimate"]))
    return values, estimates


def spacing_levels(rows: list[dict], fe: dict[str, float]) -> list[tuple[float, dict[str, float]]]:
    """(λ, signed error per quantity) of the baseline and the spacing runs, coarsest first."""
    by: dict[float, dict[str, float]] = {}
    for r in rows:
        if r.get("knob") in ("baseline", "spacing") and R.is_number(r.get("spacing")):
            errors = R.signed_sweep_errors(r, fe)
            if errors:
                by[float(r["spacing"])] = errors
    return sorted(by.items(), key=lambda kv: -kv[0])


def monotone_fit(levels: list[tuple[float, float]]) -> tuple[float, list[int]] | None:
    """Observed order from (λ, |error|), coarsest first: the least-squares slope of log|e| against
    log λ over the longest run of consecutive levels along which |e| keeps decreasing as λ shrinks
    (the finest such run if two are as long). A run that stops decreasing has met something else
    than the discretisation error, a sign change or the FE reference's own accuracy, and would bend
    the slope. None if no two consecutive levels decrease."""
    best: list[int] = []
    run = [0]
    for i in range(1, len(levels) + 1):
        if i < len(levels) and 0 < levels[i][1] < levels[i - 1][1]:
            run.append(i)
            continue
        if len(run) >= 2 and len(run) >= len(best):
            best = run
        run = [i]
    if len(best) < 2:
        return None
    xs = [math.log(levels[i][0]) for i in best]
    ys = [math.log(levels[i][1]) for i in best]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx, best


def order_text(levels: list[tuple[float, float]], fit: tuple[float, list[int]] | None,
               unresolved: list[float], estimate: float | None) -> str:
    below = ""
    if unresolved:
        below = (f"; λ = {', '.join(fnum(h, 3) for h in unresolved)} m: |error| below the FE's own "
                 f"error estimate ({pct(estimate)}), not fitted")
    if fit is None:
        return ("no order: |error| does not decrease between two consecutive resolved levels as λ "
                "shrinks" + below)
    p, idx = fit
    lo, hi = levels[idx[0]][0], levels[idx[-1]][0]
    left = len(levels) - len(idx)
    return (f"p = {p:.2f} over λ = {fnum(lo, 3)} → {fnum(hi, 3)} m ({len(idx)} levels where |error| "
            "decreases monotonically as λ shrinks" +
            (f"; {left} more level{'s' if left > 1 else ''} outside that run, not fitted" if left else "") +
            ")" + below)


def convergence_figure(page: Page, case: str, rows: list[dict]) -> str:
    fe, estimates = fe_values(page, case)
    levels = spacing_levels(rows, fe)
    anchor = f'id="convergence-{esc(case)}"'
    if len(levels) < 2:
        return (f'<figure {anchor}><figcaption><b>{esc(case)}</b>: {len(levels)} spacing level(s) '
                "in this sweep: no convergence plot (needs two).</figcaption></figure>")
    fig, ax = plt.subplots(figsize=(5.6, 4.0))
    texts = []
    for k, q in enumerate(quantity.name for quantity in page.cases[case].quantities):
        pts = [(h, abs(e[q])) for h, e in levels if q in e]
        if len(pts) < 2:
            continue
        est = estimates.get(q)
        # Below the FE solution's own accuracy PD − FE no longer measures PD: not part of a fit.
        resolved = [(h, e) for h, e in pts if est is None or e > est]
        fit = monotone_fit(resolved)
        fitted = {resolved[i][0] for i in fit[1]} if fit else set()
        color = f"C{k}"
        label = f"{q.replace('_', ' ')}: " + (f"p = {fit[0]:.2f}" if fit else "no order")
        ax.loglog([h for h, _ in pts], [max(e, 1e-12) for _, e in pts], "-", color=color, lw=0.8,
                  alpha=0.5)
        for i, (h, e) in enumerate(pts):
            ax.loglog([h], [max(e, 1e-12)], "o" if (h, e) in resolved else "X", ms=7, color=color,
                      mfc=color if h in fitted else "white", label=label if i == 0 else None)
            signed = next(es[q] for hh, es in levels if hh == h)
            ax.annotate(f"{100 * signed:+.2f} %", (h, max(e, 1e-12)), fontsize=7, xytext=(4, 4),
                        textcoords="offset points", color=color)
        if fit:
            p, idx = fit
            h0, e0 = resolved[idx[0]]
            hs = [resolved[i][0] for i in idx]
            ax.loglog(hs, [e0 * (h / h0) ** p for h in hs], "--", color=color, lw=1.6)
        if est is not None:
            ax.axhline(est, color=color, ls=":", lw=1)
        unresolved = [h for h, e in pts if (h, e) not in resolved]
        texts.append(f"<b>{esc(q.replace('_', ' '))}</b>: {order_text(resolved, fit, unresolved, est)}")
    if estimates:
        ax.plot([], [], ":", color="k", lw=1, label="FE's own error estimate")
    ax.set_xlabel("particle spacing λ (m)")
    ax.set_ylabel("|PD − FE| / FE")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax.set_title(f"{case}: error vs λ (default treatment)", fontsize=10)
    img = page.savefig(fig, f"convergence-{case}.png")
    return (f'<figure {anchor}><img src="{img}" alt="{esc(case)} error vs spacing">'
            f"<figcaption>{esc(case)}, observed order: " + "; ".join(texts) +
            ". Filled markers are fitted, hollow ones not, crosses lie below the FE's own error "
            "estimate; labels are the signed errors.</figcaption></figure>")


def pair_label(r: dict) -> str:
    pair = R.corrections_of(r)
    if r.get("knob") == "baseline":
        return f"<b>{esc(pair)}</b> (default)"
    if r.get("knob") == "corrections":
        return f"{esc(pair)} (old pair)"
    return f"{esc(pair)} (default without its {esc(str(r['knob']).replace('_', ' '))})"


def old_pairs_table(page: Page, case: str, rows: list[dict]) -> str:
    fe, _ = fe_values(page, case)
    quantities = [q.name for q in page.cases[case].quantities]
    picked = [r for r in rows if r.get("knob") in ("baseline", "corrections", "surface_correction",
                                                   "volume_correction")]
    anchor = f'id="old-pairs-{esc(case)}"'
    if not any(r.get("knob") == "corrections" for r in picked):
        return (f'<p class="note" {anchor}><b>{esc(case)}</b>: no old-pair rows in this sweep '
                "(the case file's <code>sweep: corrections:</code> list, or a sweep from before it).</p>")
    body = []
    for r in picked:
        errors = R.signed_sweep_errors(r, fe)
        sec = r.get("section_stiffness") or {}
        body.append([pair_label(r)] +
                    [f'<td class="num">{100 * errors[q]:+.2f} %</td>' if q in errors else "–"
                     for q in quantities] +
                    [f'<td class="num">{fnum(sec.get("bending"), 4)} / {fnum(sec.get("shear"), 4)}</td>',
                     f'<td class="num">{fnum(r.get("wall_seconds"), 3)}</td>',
                     f'<td class="num">{fnum(r.get("particles"))}</td>', esc(r.get("status", ""))])
    head = (["surface + volume correction"] + [f"error vs FE: {esc(q.replace('_', ' '))}" for q in quantities] +
            ["section bending / shear", "wall (s)", "particles", "status"])
    return f"<div {anchor}><h4>{esc(case)}</h4>" + table(head, body, 'class="old-pairs"') + "</div>"


def section_parts(page: Page) -> str:
    """The summary's convergence plots and old-pair tables, one per structural case with a
    `sweep:` section in its case file."""
    order = in_listed_order(page.cases, R.listed_cases(page.rec, page.meta))
    swept = [c for c in order if page.cases[c].has_sweep]
    figs, tables, missing = [], [], []
    for case in swept:
        rec = page.rec.get(f"sweep:{case}")
        if not R.ok(rec):
            missing.append(case + (" (sweep stage failed)" if rec else ""))
            continue
        rows = rec["result"]["rows"]
        figs.append(convergence_figure(page, case, rows))
        tables.append(old_pairs_table(page, case, rows))
    why = ""
    if missing:
        why = (f'<p class="note">No sweep in this report for {esc(", ".join(missing))}: the default '
               "report runs the three structures' <code>quick_sweep:</code> lists, "
               "<code>--full</code> the complete <code>sweep:</code> of every case file that has one.</p>")
    return ('<h3 id="convergence">Convergence in λ (default treatment)</h3>'
            '<p class="note">From each case\'s spacing sweep (<code>pd verify --sweep CASE</code>, '
            "the baseline and the <code>spacing</code> rows; the default report runs the case "
            "file's <code>quick_sweep:</code> lists, <code>--full</code> its <code>sweep:</code>), "
            "everything else as the scene has it. "
            "The observed order p is the slope of log|error| against log λ, fitted only over the "
            "consecutive levels where |error| decreases monotonically as λ shrinks, and only over "
            "levels whose |error| is above the FE solution's own relative error estimate (dotted "
            "lines): below it PD − FE no longer measures PD.</p>" + why + '<div class="figs">' + "".join(figs) + "</div>"
            '<h3 id="old-pairs">Old correction pairs (sweep rows)</h3>'
            '<p class="note">The sweep\'s <code>corrections</code> rows run the pairs the scenes '
            "used before the defaults, with everything else (mirror clamps, solver, λ) as the "
            "default row; the rows without one of the default's corrections come from the "
            "sweep's surface/volume knobs. Signed error, + = PD too soft; section bending / shear "
            "is the cross-section's PD/continuum stiffness (docs/theory/structures.md).</p>" + "".join(tables))
