"""The virtual-fibre section (issue 17; Olsson, Ander & Williams 2021): one subsection per figure of
the paper re-made from our runs, each a function of the page that returns its HTML. The elliptical
disk's elastic convergence (Fig. 10) and what the graded particle set saves against a uniform one
are here; the Griffith relation of §10.4 (Fig. 14) is a further entry of SUBSECTIONS."""
from __future__ import annotations

from typing import Callable

from . import records as R
from .fmt import esc, fnum
from .markup import failed_box, num_td, table
from .page import Page, plt

# The convergence case at the paper's zone grid (--full) is preferred over the CI variant.
DISK_CASES = ("elliptic-disk-convergence", "elliptic-disk")
SAVING_CASE = "elliptic-disk-saving"
REGULAR_CASE = "elliptic-disk-regular"   # the CI grid without Monte Carlo noise (--full)


def _disk_record(page: Page) -> tuple[str, dict | None]:
    for case in DISK_CASES:
        rec = page.rec.get(f"verify:{case}")
        if R.ok(rec):
            return case, rec
    return DISK_CASES[-1], page.rec.get(f"verify:{DISK_CASES[-1]}")


def _loglog(ax, series: list[tuple[str, list[dict], str, str]], label_y: str) -> None:
    """Each series (label, runs, key of the error, style) against the runs' particle counts."""
    for label, runs, key, style in series:
        if all(r.get(key) is not None for r in runs):   # records of older runs lack some keys
            ax.loglog([r["particles"] for r in runs], [r[key] for r in runs], style, label=label)
    ax.set_xlabel("particles")
    ax.set_ylabel(label_y)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)


def convergence(page: Page) -> str:
    """Fig. 10: RMS displacement error of the disk's interior against eq. 116, by particle count."""
    case, rec = _disk_record(page)
    out = ['<h3>Elliptical disk, elastic convergence (Fig. 10)</h3>',
           '<p class="note">The disk with a crack between its focal points (§10.2&ndash;10.3, '
           'Table 1, plane strain), the graded particle set of §10.2, its outer two rings of zones held '
           'at the closed form of eq. 116 (so eq. 116 is the exact solution), relaxed by ADR. '
           'The error is over every particle not held (<code>verification/cases/'
           'elliptic_disk_convergence.cpp</code>). Fig. 10 of the paper shows the same plot for '
           'five densities up to 39,200 particles but gives no rate to compare with.</p>']
    if not R.ok(rec):
        out.append(failed_box(rec, f"verification case {case}"))
        return "\n".join(out)
    d = rec["result"]
    runs = d.get("runs", [])
    order = d.get("observed_order") or {}
    rate = d.get("rate_in_particle_count")
    out.append(f'<p>Case <code>{esc(case)}</code> ({esc(" × ".join(map(str, d.get("zones", []))))} '
               f'zones): observed order in the mean spacing <b>{esc(order.get("text", "–"))}</b>, '
               f'i.e. RMS &prop; n<sup>&minus;{fnum(rate, 3)}</sup> in the particle count; gate '
               f'{"passed" if d.get("passed") else "FAILED"} ({esc(d.get("gate", ""))}).</p>')
    rows = [[num_td(str(r["pattern"])), num_td(fnum(r["particles"])), num_td(fnum(r["interior_particles"])),
             num_td(fnum(r["arms"])), num_td(fnum(r["rms"], 4)), num_td(fnum(r["l2"], 4)),
             num_td(fnum(r.get("rms_beyond_quarter_c_of_the_tips"), 4)),
             num_td(fnum(r.get("crack_opening_ratio"), 5)),
             num_td(fnum(r["rms_metres"], 4)), esc(r["status"]), num_td(fnum(r["steps"])),
             num_td(fnum(r["setup_seconds"], 3)), num_td(fnum(r["solve_seconds"], 3))] for r in runs]
    out.append(table(["per zone side", "particles", "interior", "arms", "RMS (relative)",
                      "L2 (volume-weighted)", "RMS beyond c/4 of the tips",
                      "crack opening / eq. 116", "RMS (m)", "status", "ADR steps", "set-up (s)",
                      "solve (s)"], rows, 'id="fibre-disk-table"'))
    regular = page.rec.get(f"verify:{REGULAR_CASE}")
    if R.ok(regular):
        reg = regular["result"]
        ro = reg.get("observed_order") or {}
        out.append(f'<p><code>{REGULAR_CASE}</code>: the CI case\'s 10 × 20 zones without the '
                   'Monte Carlo noise of Fig. 8 (regular zone patterns, whose arms the balance of '
                   '<code>fibre_arms.hpp</code> makes consistent at most particles): RMS '
                   + ", ".join(fnum(r["rms"], 3) for r in reg.get("runs", []))
                   + f' at {", ".join(fnum(r["particles"]) for r in reg.get("runs", []))} particles; '
                   f'observed order {esc(ro.get("text", "–"))}.</p>')
    if runs:
        fig, ax = plt.subplots(figsize=(5.6, 3.8))
        grid = " × ".join(map(str, d.get("zones", [])))
        series = [(f"RMS, {grid} zones", runs, "rms", "o-"),
                  (f"L2 (volume-weighted), {grid} zones", runs, "l2", "s--"),
                  ("RMS beyond c/4 of the tips", runs, "rms_beyond_quarter_c_of_the_tips", "^:")]
        fast = page.rec.get("verify:elliptic-disk")
        if case != "elliptic-disk" and R.ok(fast):
            series.append(("RMS, 10 × 20 zones (CI case)", fast["result"].get("runs", []), "rms", "v-"))
        if R.ok(regular):
            series.append(("RMS, 10 × 20 zones, no noise", regular["result"].get("runs", []), "rms", "D-"))
        _loglog(ax, series, "displacement error / norm of eq. 116")
        fig.tight_layout()
        out.append(f'<img src="{page.savefig(fig, "fibre-disk-convergence.png")}" '
                   'alt="RMS displacement error against particle count (Fig. 10)">')
    return "\n".join(out)


def _match_row(m: dict) -> list[str]:
    if "uniform_particles" not in m:
        return [num_td(fnum(m["graded_particles"])), num_td(fnum(m["l2"], 4)), "–", "–",
                num_td(fnum(m["graded_seconds"], 3)), "–", "–", esc(m["how"])]
    return [num_td(fnum(m["graded_particles"])), num_td(fnum(m["l2"], 4)),
            num_td(fnum(m["uniform_particles"])), num_td(f'{m["particle_ratio"]:.3g}×'),
            num_td(fnum(m["graded_seconds"], 3)), num_td(fnum(m["uniform_seconds"], 3)),
            num_td(f'{m["time_ratio"]:.3g}×'), esc(m["how"])]


def saving(page: Page) -> str:
    """What the graded set saves: uniform sets of the same disk against the graded ones."""
    rec = page.rec.get(f"verify:{SAVING_CASE}")
    out = ['<h3>What the variable particle size saves</h3>',
           '<p class="note">The same disk and held zone filled with one spacing everywhere, against '
           'the graded sets, with the paper\'s Monte Carlo noise and without it; particle count and '
           'time (set-up and solve) of a uniform set with the graded one\'s volume-weighted L2 '
           'error, read off the uniform sets\' own log-log line (<code>pd verify '
           'elliptic-disk-saving</code>). The L2 error compares the two fields; the per-particle '
           'RMS would weight each set\'s error where its particles are, at the crack tips for the '
           'graded set. No match is given where the uniform sets\' error does not fall.</p>']
    if rec is None:
        out.append('<p class="note"><i>not run in this mode (pd_report.py --full)</i></p>')
        return "\n".join(out)
    if not R.ok(rec):
        out.append(failed_box(rec, f"verification case {SAVING_CASE}"))
        return "\n".join(out)
    d = rec["result"]
    rows = []
    for key, label in (("noisy", "Monte Carlo noise"), ("regular", "regular patterns")):
        for m in (d.get(key) or {}).get("equal_error", []):
            rows.append([esc(label)] + _match_row(m))
    out.append(table(["arrangement", "graded particles", "L2 error", "uniform particles for it",
                      "ratio", "graded time (s)", "uniform time (s)", "ratio", "uniform figures"],
                     rows, 'id="fibre-saving-table"'))
    series = []
    for key, label, style in (("noisy", "noise", "-"), ("regular", "regular", ":")):
        sets = d.get(key) or {}
        if sets.get("graded"):
            series.append((f"graded, {label}", sets["graded"], "l2", "o" + style))
        if sets.get("uniform"):
            series.append((f"uniform, {label}", sets["uniform"], "l2", "s" + style))
    if series:
        fig, ax = plt.subplots(figsize=(5.6, 3.8))
        _loglog(ax, series, "L2 displacement error / L2 norm of eq. 116")
        fig.tight_layout()
        out.append(f'<img src="{page.savefig(fig, "fibre-disk-saving.png")}" '
                   'alt="L2 error against particle count, graded and uniform">')
    return "\n".join(out)


def kernel_speed(page: Page) -> str:
    """Bond updates per second of the fibre kernel beside the bond-based one on the same particles."""
    rec = page.rec.get("fibre-bench")
    out = ['<h3>Fibre kernel speed</h3>',
           '<p class="note"><code>pd bench SCENE --bond-model micro-elastic|virtual-fibres '
           '--threads 1</code>, the two alternated round by round; the ratio is taken per round. '
           'One bond update is one arm\'s force computed once. The fibre kernel makes two passes '
           'over the rows (the mean strain of eq. 73, then the forces) in scalar code; the '
           'bond-based one is one vectorised pass. The bond counts differ where the scene takes the '
           'library\'s default <code>volume_correction: gradient</code>: the bond-based model '
           'then drops the bonds its weights set to zero (beyond 2&lambda;) and its ghost layers '
           'reach only as deep as the bonds it keeps, while the fibre model reads '
           '<code>gradient</code> as its fourth-moment weights and keeps the whole horizon and '
           'ghosts a horizon deep. Model A sets no correction: there both hold the same bonds.</p>']
    if not R.ok(rec):
        out.append(failed_box(rec, "the fibre-bench stage"))
        return "\n".join(out)
    d = rec["result"]
    rows = []
    for sc in d.get("scenes", []):
        b, f = sc["models"]["micro-elastic"], sc["models"]["virtual-fibres"]
        rows.append([f'<code>{esc(sc["scene"])}</code>', num_td(fnum(b["particles"])), num_td(fnum(b["bonds"])),
                     num_td(fnum(b["median"], 3)), num_td(fnum(f["particles"])), num_td(fnum(f["bonds"])),
                     num_td(fnum(f["median"], 3)), num_td(f'{sc["ratio_median"]:.3g}'),
                     "yes" if b["under_load"] or f["under_load"] else "no"])
    out.append(table(["scene", "bond-based particles", "bonds", "updates/s", "fibre particles",
                      "arms", "updates/s", "fibre / bond-based (median of rounds)", "under load"],
                     rows, 'id="fibre-bench-table"'))
    out.append(f'<p class="note">{d.get("rounds")} rounds; load averages before each round and '
               f'after: {esc(", ".join(d.get("loadavg", [])))}.</p>')
    return "\n".join(out)


SUBSECTIONS: list[Callable[[Page], str]] = [convergence, saving, kernel_speed]


def section(page: Page) -> str:
    parts = ['<section id="fibres"><h2>Virtual fibres</h2>']
    parts += [f(page) for f in SUBSECTIONS]
    parts.append("</section>")
    return "\n".join(parts)
