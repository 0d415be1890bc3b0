"""Scenes written as a new user would (verification/scenes/user/), each run by `pd verify
SCENE.yaml` beside deal.II on the same continuum problem (`pd-fem --scene`): per probe PD, FE, their
difference and the FE's own error estimate, with both wall times; a line probe's points also as a
profile, PD against FE along the line."""
from __future__ import annotations

from . import records as R
from .fmt import esc, fnum
from .markup import failed_box, num_td, table
from .page import Page, plt


def line_profiles(page: Page, scene: str, probes: list[dict]) -> list[str]:
    """One figure per line probe of the scene: PD and FE against the distance along the line
    (the points `pd verify` writes with `line`, `line_index` and `line_distance`)."""
    lines: dict[str, list[dict]] = {}
    for p in probes:
        if p.get("line") is not None and R.is_number(p.get("pd")) and R.is_number(p.get("fe")):
            lines.setdefault(p["line"], []).append(p)
    out = []
    for line, pts in sorted(lines.items()):
        pts.sort(key=lambda p: p.get("line_index", 0))
        s = [p.get("line_distance", 0.0) for p in pts]
        fig, ax = plt.subplots(figsize=(5.6, 3.6))
        ax.plot(s, [p["fe"] for p in pts], "-", color="C1", lw=1.6, label="FE (deal.II)")
        ax.plot(s, [p["pd"] for p in pts], "o", color="C0", ms=4, label="PD")
        ax.set_xlabel("distance along the line (m)")
        ax.set_ylabel(str(pts[0].get("quantity", "")))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(f"{scene}: {line}", fontsize=10)
        img = page.savefig(fig, f"profile-{scene}-{line}.png")
        worst = max(abs(p.get("judged_difference") or 0.0) for p in pts)
        out.append(f'<figure id="profile-{esc(scene)}-{esc(line)}"><img src="{img}" '
                   f'alt="{esc(scene)} {esc(line)} profile"><figcaption><b>{esc(scene)}</b>, line '
                   f'probe <b>{esc(line)}</b>: {len(pts)} points, PD (markers) against FE (line); '
                   f'largest judged difference {100 * worst:.2f} %.</figcaption></figure>')
    return out


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
    figures = []
    for name, rec in recs.items():
        if not R.ok(rec):
            out.append(failed_box(rec, f"pd verify {name}"))
            continue
        d = rec["result"]
        timing = f"PD {fnum(d.get('pd_seconds'), 3)} s, FE {fnum(d.get('fe_seconds'), 3)} s"
        figures += line_profiles(page, name.split(":", 1)[-1], d.get("probes") or [])
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
    out += figures
    out.append("</section>")
    return "\n".join(out)
