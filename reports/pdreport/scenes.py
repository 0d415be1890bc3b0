"""Scenes written as a new user would (verification/scenes/user/), each run by `pd verify
SCENE.yaml` beside deal.II on the same continuum problem (`pd-fem --scene`): per probe PD, FE, their
difference and the FE's own error estimate, with both wall times."""
from __future__ import annotations

from . import records as R
from .fmt import esc, fnum
from .markup import failed_box, num_td, table
from .page import Page


def section(page: Page) -> str:
    recs = {n: r for n, r in sorted(page.rec.items()) if r.get("group") == "scene"}
    out = ['<section id="scenes"><h2>Your scenes vs deal.II</h2>',
           '<p class="note">Each scene of <code>verification/scenes/user/</code> run by '
           '<code>pd verify SCENE.yaml --fe-coarse</code>: the PD run, then <code>pd-fem --scene</code> '
           'on the same file (three Q2 levels, Richardson). PD vs FE is (PD &minus; FE) / FE; '
           'the FE estimate is its own extrapolation error. Not gated: a user\'s scene has no '
           'tolerance of its own.</p>']
    if not recs:
        out.append('<p class="note"><i>not run in this mode</i></p>')
    rows = []
    for name, rec in recs.items():
        if not R.ok(rec):
            out.append(failed_box(rec, f"pd verify {name}"))
            continue
        d = rec["result"]
        timing = f"PD {fnum(d.get('pd_seconds'), 3)} s, FE {fnum(d.get('fe_seconds'), 3)} s"
        for i, p in enumerate(d.get("probes") or []):
            diff = p.get("relative_difference")
            est = p.get("fe_relative_error_estimate")
            rows.append([esc(name.split(":", 1)[1]) if i == 0 else "", esc(p.get("name")),
                         num_td(fnum(p.get("pd"), 6)), num_td(fnum(p.get("fe"), 6)),
                         num_td(f"{100 * diff:+.2f} %" if R.is_number(diff) else "&ndash;"),
                         num_td(f"{100 * est:.2g} %" if R.is_number(est) else "&ndash;"),
                         timing if i == 0 else ""])
    if rows:
        out.append(table(["scene", "probe", "PD", "FE", "PD vs FE", "FE est.", "wall"],
                         rows, 'id="scenes-table"'))
    out.append("</section>")
    return "\n".join(out)
