"""The scorecard that opens the page: one row per case of `pd verify --list`, a line per gated
quantity (quantity, PD, reference and which, signed error, gate), with the case's wall time and
verdict. It is what a reader takes in at a glance, so it stays narrow enough for a 1280 px window
(the browser test measures that) and leaves every other number to the case's own section
(casedetails.py). The summary table reads its lines from here too, so the two cannot disagree."""
from __future__ import annotations

from dataclasses import dataclass, field

from . import records as R
from .fmt import esc, fnum, pct
from .page import Page

# Error keys whose PD and reference values the case JSON stores under another name (block-tension
# measures the elongation as the loaded end's displacement, the contraction as a lateral strain).
VALUE_KEY = {"elongation": "end_displacement", "lateral_contraction": "lateral_strain"}

# What a case's reference is, where the error key does not say it (`..._vs_fe`, `..._vs_paper`):
# each run's `reference_kind` in its case.yaml, from the meta's `pd verify --list --json` (entries()).
REFERENCE_KIND: dict[str, str] = {}
KIND_OF_SUFFIX = {"fe": "FE (deal.II)", "paper": "paper", "ec2": "Eurocode 2",
                  "timoshenko": "analytical (Timoshenko)", "kirchhoff": "analytical (Kirchhoff)"}


@dataclass
class Line:
    """One gated quantity of a case."""
    quantity: str
    pd: object = None
    reference: object = None
    kind: str = ""
    error: float | None = None
    signed: bool = False          # False: the case reports |error| only
    gate: str = ""                # the gate of this quantity, formatted ("≤ 1 %")
    within: bool | None = None    # the error against that gate


@dataclass
class Entry:
    case: str
    verdict: str                  # pass, fail, measured, not-run, stage-failed
    lines: list[Line] = field(default_factory=list)
    gate_text: str = ""           # a gate stated in words, for all lines at once
    wall: object = None
    note: str = ""                # HTML in place of the lines (not run, failed, sweep)
    anchor: str = ""


def entries(page: Page) -> list[Entry]:
    verify = page.group("verify")
    meta_summary = dict((c, t) for c, t in page.meta.get("cases", []))
    REFERENCE_KIND.clear()
    REFERENCE_KIND.update((r["name"], r["reference_kind"]) for r in page.meta.get("case_metadata", [])
                          if r.get("reference_kind"))
    out = []
    for case in R.listed_cases(page.rec, page.meta):
        rec = verify.get(f"verify:{case}")
        if rec is None and case.endswith("-sweep"):
            out.append(sweep_entry(page, case))
        elif rec is None:
            why = ("slow: <code>--full</code> runs it" if "(slow)" in meta_summary.get(case, "")
                   else "not run")
            out.append(Entry(case, "not-run", note=f"<i>{why}</i>"))
        elif not R.ok(rec):
            out.append(Entry(case, "stage-failed", note="the stage failed (see Stages)",
                             wall=rec.get("seconds")))
        else:
            out.append(case_entry(page, case, rec["result"]))
    return out


def case_entry(page: Page, case: str, d: dict) -> Entry:
    base = case.removesuffix("-fast")
    gate = d.get("gate")
    if base in page.cases and isinstance(d.get("reference"), dict):
        lines = structure_lines(d)
    else:
        lines = gated_lines(case, d)
    text = gate if isinstance(gate, str) else ""
    if not lines:
        lines = reported_lines(case, d) or [Line(short_text(d.get("quantity", ""), 48))]
    verdict = ("measured" if text.startswith("none") else "pass" if d.get("passed") else "fail")
    return Entry(case, verdict, lines, gate_text=text, wall=d.get("wall_seconds"),
                 anchor=f"case-{case}")


def structure_lines(d: dict) -> list[Line]:
    pdv, ref, gate = d.get("pd", {}), d.get("reference", {}), d.get("gate", {})
    gate = gate if isinstance(gate, dict) else {}
    lines = []
    for q, v in pdv.items():
        fe = (ref.get(q) or {}).get("fe")
        err = v / fe - 1.0 if R.is_number(v) and R.is_number(fe) and fe else None
        g = gate.get(f"{q}_vs_fe")
        lines.append(Line(q.replace("_", " "), v, fe, KIND_OF_SUFFIX["fe"], err, True,
                          f"≤ {pct(g)}" if R.is_number(g) else "",
                          abs(err) <= g if err is not None and R.is_number(g) else None))
    reg = d.get("regression") or {}
    drifts = [(r.get("relative_change"), r.get("tolerance")) for r in reg.values() if isinstance(r, dict)]
    drifts = [(c, t) for c, t in drifts if R.is_number(c)]
    if drifts:
        worst, tol = max(drifts, key=lambda p: p[0])
        lines.append(Line("change vs stored value", kind="stored (case file)", error=worst,
                          gate=f"≤ {pct(tol)}" if R.is_number(tol) else "",
                          within=worst <= tol if R.is_number(tol) else None))
    return lines


def gated_lines(case: str, d: dict) -> list[Line]:
    """A line per numeric gate (bar-vibration's period ≤ 1 %, cycles ≥ 5)."""
    gate, err, signed = d.get("gate"), d.get("error") or {}, d.get("signed_error") or {}
    if not isinstance(gate, dict) or not isinstance(err, dict):
        return []
    lines = []
    for k, g in gate.items():
        if not R.is_number(g):
            continue
        if k.startswith("min_"):      # a floor on a count the case reports among its PD values
            v = (d.get("pd") or {}).get(k.removeprefix("min_"))
            lines.append(Line(k.removeprefix("min_").replace("_", " "), v, gate=f"≥ {fnum(g)}",
                              within=v >= g if R.is_number(v) else None))
        elif R.is_number(err.get(k)):
            line = value_line(case, d, k, err[k], signed.get(k))
            line.gate = f"≤ {pct(g)}"
            line.within = abs(line.error) <= g
            lines.append(line)
    return lines


def reported_lines(case: str, d: dict, most: int = 3) -> list[Line]:
    """A case gated in words: the errors it reports (those it also signs first: block-tension signs
    exactly its gated two), at most `most`; the rest are in the case's section."""
    err, signed = d.get("error"), d.get("signed_error") or {}
    if not isinstance(err, dict):
        return []
    flat = {k: v for k, v in R.flatten(err).items() if R.is_number(v)}
    keys = [k for k in flat if k in signed] or list(flat)
    return [value_line(case, d, k, flat[k], signed.get(k)) for k in keys[:most]]


def value_line(case: str, d: dict, key: str, error: float, signed: object) -> Line:
    a, _, b = key.partition("_vs_")
    pdv, ref = find_values(d, VALUE_KEY.get(a, a), b)
    kind = KIND_OF_SUFFIX.get(b) or REFERENCE_KIND.get(case, "reference")
    if R.is_number(signed):
        return Line(a.replace("_", " "), pdv, ref, kind, float(signed), True)
    if R.is_number(pdv) and R.is_number(ref) and ref:
        s = pdv / ref - 1.0
        if abs(abs(s) - abs(error)) <= 1e-9 + 1e-3 * abs(error):   # the error is PD vs this reference
            return Line(a.replace("_", " "), pdv, ref, kind, s, True)
    return Line(a.replace("_", " "), pdv, ref, kind, float(error), error < 0)


def find_values(d: dict, a: str, b: str) -> tuple[object, object]:
    """The PD and reference values behind an error `a[_vs_b]`, found by name in the case's `pd` and
    `reference` (flattened, dots as underscores): the key itself, else the one key that starts with
    it (and names b, if several do)."""
    def flat(x: object) -> dict[str, object]:
        return {k.replace(".", "_"): v for k, v in R.flatten(x).items() if R.is_number(v)}

    def pick(values: dict[str, object], exact: list[str], test) -> object:
        for e in exact:
            if e in values:
                return values[e]
        hits = [k for k in values if test(k)]
        if len(hits) > 1 and b:
            hits = [k for k in hits if b in k]
        return values[hits[0]] if len(hits) == 1 else None

    pdv = pick(flat(d.get("pd")), [a], lambda k: k.startswith(a))
    ref = pick(flat(d.get("reference")), [f"{a}_{b}", a] if b else [a],
               lambda k: a in k and (not b or b in k))
    return pdv, ref


def sweep_entry(page: Page, case: str) -> Entry:
    base = case.removesuffix("-sweep")
    rec = page.rec.get(f"sweep:{base}")
    anchor = f"convergence-{base}"
    if rec is None:
        return Entry(case, "not-run", note="<i>sweep not run in this report: <code>--full</code> runs it</i>")
    if not R.ok(rec):
        return Entry(case, "stage-failed", note="the sweep stage failed (see Accuracy vs time)",
                     wall=rec.get("seconds"))
    rows = rec["result"]["rows"]
    reduced = " (reduced)" if rec["result"].get("reduced") else ""
    return Entry(case, "measured", wall=rec.get("seconds"), anchor=anchor,
                 note=f'{len(rows)} runs{reduced}: <a href="#{anchor}">convergence in λ</a>, '
                      f'<a href="#old-pairs-{base}">old correction pairs</a>')


def short_text(s: object, n: int) -> str:
    s = str(s)
    return s if len(s) <= n else s[: n - 1].rsplit(" ", 1)[0] + " …"


# ---- HTML ---------------------------------------------------------------------------------------

VERDICT = {"pass": ("v-pass", "PASS"), "fail": ("v-fail", "FAIL"), "measured": ("v-info", "measured"),
           "not-run": ("v-info", "not run"), "stage-failed": ("v-fail", "FAILED")}


def signed_pct(v: float | None, signed: bool) -> str:
    if v is None:
        return "–"
    if not signed:
        return f"±{100 * abs(v):.3g} %"
    return f"{100 * v:+.3g} %"


def rows_html(e: Entry) -> str:
    cls, word = VERDICT[e.verdict]
    name = f'<a href="#{e.anchor}">{esc(e.case)}</a>' if e.anchor else esc(e.case)
    wall = fnum(e.wall, 3) if R.is_number(e.wall) else "–"
    n = max(1, len(e.lines))
    span = f' rowspan="{n}"' if n > 1 else ""
    head = f'<td class="case"{span}><b>{name}</b></td>'
    tail = (f'<td class="num"{span}>{wall}</td>'
            f'<td class="verdict {cls}"{span}>{word}</td>')
    if not e.lines:
        return (f'<tr data-case="{esc(e.case)}">{head}<td colspan="6">{e.note or "–"}</td>'
                f"{tail}</tr>")
    out = []
    for i, line in enumerate(e.lines):
        over = ' class="num over"' if line.within is False else ' class="num"'
        cells = [f"<td>{esc(line.quantity)}</td>", f'<td class="num">{fnum(line.pd)}</td>',
                 f'<td class="num">{fnum(line.reference) if line.reference is not None else ""}</td>',
                 f'<td class="kind">{esc(line.kind)}</td>',
                 f"<td{over}>{signed_pct(line.error, line.signed)}</td>"]
        if e.gate_text and not any(l.gate for l in e.lines):
            if i == 0:
                cells.append(f'<td class="gate-text"{span}>{esc(e.gate_text)}</td>')
        else:
            cells.append(f'<td class="gate{" over" if line.within is False else ""}">{esc(line.gate) or "–"}</td>')
        attrs = f'data-case="{esc(e.case)}"' if i == 0 else f'data-case-line="{esc(e.case)}"'
        out.append(f"<tr {attrs}>" + (head if i == 0 else "") + "".join(cells) +
                   (tail if i == 0 else "") + "</tr>")
    return "".join(out)


def section(page: Page) -> str:
    es = entries(page)
    count = {v: sum(1 for e in es if e.verdict == v) for v in VERDICT}
    status = (f'<p class="{"fail" if count["fail"] or count["stage-failed"] else "pass"}">'
              f"{len(es)} cases: {count['pass']} pass, {count['fail']} fail"
              + (f", {count['stage-failed']} failed to run" if count["stage-failed"] else "")
              + f", {count['measured']} measurements without a gate, {count['not-run']} not run "
              "in this report.</p>")
    head = ("<tr><th>case</th><th>quantity</th><th>PD</th><th>reference</th><th>which</th>"
            "<th>error</th><th>gate</th><th>wall (s)</th><th>result</th></tr>")
    note = ('<p class="note">error = (PD − reference) / reference, + = PD larger; ± where the case '
            "reports |error| only. FE = deal.II Q2, finest mesh, extrapolated. A red error exceeds "
            "its gate. Everything else a case measured is in its own section "
            '(<a href="#cases">Cases</a>).</p>')
    return ('<section id="scorecard"><h2>Scorecard</h2>' + status +
            f'<table id="scorecard-table"><thead>{head}</thead><tbody>' +
            "".join(rows_html(e) for e in es) + "</tbody></table>" + note + "</section>")
