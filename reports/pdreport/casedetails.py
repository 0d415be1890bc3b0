"""Each case's own section: every number its JSON holds (flattened), so the scorecard and the
summary can stay short and a reader still finds bond-count's counts or a beam's error budget one
click away (the scorecard links here)."""
from __future__ import annotations

from . import records as R
from .fmt import esc, fnum
from .markup import failed_box
from .page import Page

# What a reader looks for first; the rest (settings, run summaries, …) is folded away.
MAIN = ("quantity", "pd", "reference", "error", "signed_error", "gate", "regression", "relaxation",
        "error_budget", "section_stiffness", "particles", "bonds", "steps", "wall_seconds", "note")
# Already shown elsewhere on the page, or bulky: not repeated here.
SKIP = ("lines", "stdout_tail", "summary", "case")


def value_text(v: object) -> str:
    if isinstance(v, str):
        return esc(v)
    return fnum(v, 6)


def kv_table(flat: dict[str, object]) -> str:
    # Only numbers stay on one line: a long text value must wrap inside the case's column.
    rows = "".join(f"<tr><td><code>{esc(k)}</code></td>" +
                   (f'<td class="num">{value_text(v)}</td>' if R.is_number(v) else f"<td>{value_text(v)}</td>") +
                   "</tr>" for k, v in flat.items())
    return f'<table class="kv"><tbody>{rows}</tbody></table>'


def case_block(case: str, rec: dict | None, summary: str) -> str:
    head = f'<div class="case" id="case-{esc(case)}"><h3>{esc(case)}</h3>'
    if summary:
        head += f'<p class="note">{esc(summary)}</p>'
    if rec is None:
        return head + '<p class="note"><i>not run in this mode</i></p></div>'
    if not R.ok(rec):
        return head + failed_box(rec, f"verification case {case}") + "</div>"
    d = rec["result"]
    main, rest, lists = {}, {}, []
    for k, v in d.items():
        if k in SKIP:
            continue
        if isinstance(v, list):
            lists.append(k)
            continue
        target = main if k in MAIN else rest
        flat = R.flatten(v, f"{k}.") if isinstance(v, dict) else {k: v}
        target.update({kk: vv for kk, vv in flat.items()})
    out = head + kv_table(main)
    if rest:
        out += (f"<details><summary>{len(rest)} more values (settings, run summary, …)</summary>"
                f"{kv_table(rest)}</details>")
    if lists:
        out += ('<p class="note">Tables and curves in report.json (<code>data["verify:'
                f'{esc(case)}"]</code>): ' + ", ".join(f"<code>{esc(k)}</code>" for k in lists) + ".</p>")
    return out + "</div>"


def section(page: Page) -> str:
    summaries = dict((c, t) for c, t in page.meta.get("cases", []))
    blocks = []
    for case in R.listed_cases(page.rec, page.meta):
        if case.endswith("-sweep"):
            continue      # a sweep's rows are in Accuracy vs time
        rec = page.rec.get(f"verify:{case}")
        blocks.append(case_block(case, rec, summaries.get(case, "")))
    return ('<section id="cases"><h2>Cases</h2><p class="note">Every number each case wrote '
            "(<code>pd verify CASE</code> → <code>CASE.json</code>), flattened; lists such as "
            "deflection lines and sweep rows are in their sections and in report.json.</p>"
            f'<div class="cases">{"".join(blocks)}</div></section>')
