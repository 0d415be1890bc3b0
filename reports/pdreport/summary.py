"""The summary table: one row per verification case of `pd verify --list`, PD beside FE, theory
and Miranda's own PD–FE agreement, with the gate and its verdict."""
from __future__ import annotations

from . import convergence, scorecard
from . import records as R
from .cases import in_listed_order
from .fmt import esc, fnum, pct, short
from .markup import failed_box, num_td, table
from .page import Page

HEAD = ["case", "quantity", "PD", "FE (deal.II)", "analytical", "error vs FE", "error vs analytical",
        "Miranda's PD–FE agreement", "particles / bonds"]
BLANK = ["–"] * (len(HEAD) - 2)


def section(page: Page) -> str:
    verify = page.group("verify")
    rows, attrs = [], []
    listed = R.listed_cases(page.rec, page.meta)
    for case in listed:
        rec = verify.get(f"verify:{case}")
        attrs.append(f'data-case="{esc(case)}"')
        if rec is None and case.endswith("-sweep"):
            rows.append(sweep_summary_row(page, case))
            continue
        if rec is None:
            summ = dict((c, t) for c, t in page.meta.get("cases", [])).get(case, "")
            why = ("not run in the default report: <code>pd verify --list</code> marks it slow; "
                   "<code>--full</code> runs it") if "(slow)" in summ else "not run"
            rows.append([f"<b>{esc(case)}</b>", f"<i>{why}</i><br><small>{esc(summ)}</small>"] + BLANK)
            continue
        if not R.ok(rec):
            err = esc((rec.get("error") or "")[:400])
            rows.append([f"<b>{esc(case)}</b>", f'<span class="fail">stage FAILED</span><br><small>{err}</small>']
                        + BLANK)
            continue
        rows.append(summary_row(page, case, rec["result"]))
    if not verify:
        return ('<section id="summary"><h2>Summary</h2>' +
                failed_box(None, "pd verify (no verification stage ran)") +
                table(HEAD, [], 'id="summary-table"') + convergence.section_parts(page) + "</section>")
    levels = ", ".join(f"{c} {pct(page.cases[c].paper_agreement)}"
                       for c in in_listed_order(page.cases, listed) if page.cases[c].paper_agreement)
    note = ("<p class=\"note\">Errors are signed and relative, (PD − reference)/reference. FE = "
            "finest-mesh-extrapolated deal.II Q2 value (fem_reference/reference); analytical = "
            "Timoshenko (Euler–Bernoulli in brackets) for the beams, Kirchhoff for the plate, the "
            "modal series / σ/E for the bar and the block. Miranda's column is the agreement the "
            f"paper reports between its PD and FE models ({esc(levels)}); ours is in <i>error vs "
            "FE</i>, gates, verdicts and wall times are in the scorecard. For the structures, "
            "<i>budget</i> splits PD/FE into the factor the cross-section's own stiffness predicts "
            "and what the supports, load and ends add (docs/theory/structures.md).</p>")
    fails = [n for n, r in verify.items() if R.ok(r) and not r["result"].get("passed")]
    failtxt = (f"<p class=\"fail\">Gates failing: {esc(', '.join(f.split(':')[1] for f in fails))}</p>"
               if fails else "<p class=\"pass\">All gates that ran passed.</p>")
    return ('<section id="summary"><h2>Summary</h2>' + failtxt + treatment(page) + note +
            table(HEAD, rows, 'id="summary-table"', attrs) + convergence.section_parts(page) +
            "</section>")


def sweep_summary_row(page: Page, case: str) -> list[str]:
    base = case.removesuffix("-sweep")
    rec = page.rec.get(f"sweep:{base}")
    head = [f"<b>{esc(case)}</b>"]
    if rec is None:
        return head + ['accuracy-vs-time sweep: <i>not run in this report</i> (<code>--full</code> runs it)'] + BLANK
    if not R.ok(rec):
        return head + ['<span class="fail">sweep stage FAILED</span> (see Accuracy vs time)'] + BLANK
    res = rec["result"]
    pts = [(R.sweep_error(r), r) for r in res["rows"] if R.sweep_error(r) is not None]
    best = min(pts, key=lambda p: p[0]) if pts else None
    txt = (f'<a href="#accuracy">accuracy-vs-time sweep</a> (<a href="#convergence-{esc(base)}">'
           f'convergence in λ</a>): {len(res["rows"])} runs') + (
        " (reduced)" if res.get("reduced") else "")
    if best:
        txt += f'; best {esc(best[1].get("knob"))} = {esc(short(best[1].get("knob_value")))}'
    return head + [txt, "–", "–", "–", num_td(f"|{pct(best[0])}|" if best else "–"), "–", "–", "–"]


def size_td(d: dict) -> str:
    particles, bonds = R.run_size(d)
    return num_td(f"{fnum(particles)}<br>{fnum(bonds)}")


def summary_row(page: Page, case: str, d: dict) -> list[str]:
    base = case.removesuffix("-fast")
    ref = d.get("reference", {})
    quantity = esc(d.get("quantity", "")) + f'<br><small><a href="#case-{esc(case)}">all its numbers</a></small>'
    if base in page.cases and isinstance(ref, dict):
        return structure_row(page, case, d, quantity)
    # Other cases: the scorecard's lines; every other number they wrote is in their own section.
    lines = scorecard.case_entry(page, case, d).lines
    pd_txt = "<br>".join(f"{esc(l.quantity)}: {fnum(l.pd)}" for l in lines if l.pd is not None)
    ref_txt = "<br>".join(f"{fnum(l.reference)} <small>({esc(l.kind)})</small>" for l in lines
                          if l.reference is not None)
    err_txt = "<br>".join(f"{esc(l.quantity)}: {scorecard.signed_pct(l.error, l.signed)}"
                          for l in lines if l.error is not None)
    return [f"<b>{esc(case)}</b>", quantity, num_td(pd_txt or "–"), "–", num_td(ref_txt or "–"), "–",
            num_td(err_txt or "–"), "–", size_td(d)]


def signed(v: object, r: object) -> str:
    ok = R.is_number(v) and R.is_number(r) and r
    return scorecard.signed_pct(v / r - 1.0 if ok else None, True)  # type: ignore[operator]


def structure_row(page: Page, case: str, d: dict, quantity: str) -> list[str]:
    pdv, ref, err = d.get("pd", {}), d.get("reference", {}), d.get("error", {})
    pd_l, fe_l, an_l, efe_l, ean_l = [], [], [], [], []
    for q, v in pdv.items():
        r = ref.get(q, {})
        pd_l.append(f"{esc(q)}: {fnum(v)}")
        fe_l.append(fnum(r.get("fe")))
        if "timoshenko" in r:
            an_l.append(f"T {fnum(r['timoshenko'])} (EB {fnum(r.get('euler_bernoulli'))})")
            ean_l.append(f"T {signed(v, r['timoshenko'])} (EB {signed(v, r.get('euler_bernoulli'))})")
        elif "kirchhoff" in r:
            an_l.append(f"K {fnum(r['kirchhoff'])}")
            ean_l.append(f"K {signed(v, r['kirchhoff'])}")
        else:
            an_l.append("–")
            ean_l.append("–")
        efe_l.append(signed(v, r.get("fe")))
    for k, v in err.items():
        if k.startswith("line_"):
            efe_l.append(f'<small class="wrap">{esc(k.removeprefix("line_").replace("_max_over_max_fe", ""))} '
                         f"line max: |{pct(v)}|</small>")
    budget = d.get("error_budget", {})
    first = next((b for b in budget.values() if isinstance(b, dict)), None)
    if first:
        sec = d.get("section_stiffness", {})
        efe_l.append(f"<small class=\"wrap\">budget: section ×{fnum(first.get('section_factor'), 4)} "
                     f"(bending {fnum(sec.get('bending'), 3)}, shear {fnum(sec.get('shear'), 3)}), "
                     f"supports/load/ends ×{fnum(first.get('remaining_factor'), 4)}</small>")
    paper = pct(page.cases[case.removesuffix("-fast")].paper_agreement)
    return [f"<b>{esc(case)}</b>", quantity, num_td("<br>".join(pd_l)), num_td("<br>".join(fe_l)),
            num_td("<br>".join(an_l)), num_td("<br>".join(efe_l)), num_td("<br>".join(ean_l)),
            num_td(paper), size_td(d)]


def treatment(page: Page) -> str:
    """The corrections the structural cases ran with, as their JSON reports them."""
    used = {}
    for case in page.cases:
        rec = page.rec.get(f"verify:{case}")
        s = (rec or {}).get("result", {}).get("settings", {}) if R.ok(rec) else {}
        if "surface_correction" in s:
            used[case] = (f"{s['surface_correction']} + {s['volume_correction']}, "
                          f"{s.get('mirror_coupling', '?')} clamps")
    if not used:
        return ""
    by: dict[str, list[str]] = {}
    for c, t in used.items():
        by.setdefault(t, []).append(c)
    return ('<p class="reading">Structural cases ran with ' +
            "; ".join(f"{esc(t)} ({esc(', '.join(cs))})" for t, cs in by.items()) +
            " (surface + volume correction, mirror coupling): the errors below are those of "
            'this treatment; the old pairs are sweep rows <a href="#old-pairs">further down</a>.</p>')
