"""The MPI section: Model C split over 1, 2 and 4 ranks (reports/mpi/scaling.py) — solve time and
speed-up, particles, halo copies, memory and halo bytes per step of each rank, and whether the
answers were bitwise those of one rank."""
from __future__ import annotations

from . import records as R
from .fmt import esc, fnum
from .markup import failed_box, num_td, table
from .page import Page, plt

MIB = 1024.0 * 1024.0


def section(page: Page) -> str:
    out = ['<section id="mpi"><h2>MPI: one model over several ranks</h2>',
           '<p class="note"><code>mpirun -np N pd run SCENE</code>: Zoltan (RCB) assigns the '
           'particles, each rank holds its own and a halo of every particle their forces need, '
           'halo positions are exchanged before the dependants are set each step, and every sum '
           'is exact (<code>core/exact_sum.hpp</code>), so runs on any rank count are bitwise '
           'identical (ctest label <code>mpi</code>: Model A, the clamped beam with ghosts and '
           'quadratic clamps, and a fracture case under ADR, on 1, 2 and 4 ranks, and a SIGKILL '
           '+ restart). The machine has 2 cores: 4 ranks are oversubscribed, so their speed-up '
           'cannot exceed 2. The weak-scaling model for 10<sup>6</sup>&ndash;10<sup>9</sup> '
           'particles is in the README (&ldquo;Running on several ranks&rdquo;).</p>']
    rec = page.rec.get("mpi")
    if not R.ok(rec):
        out.append(failed_box(rec, "reports/mpi/scaling.py"))
        out.append("</section>")
        return "\n".join(out)
    d = rec["result"]
    same = d.get("bitwise_identical")
    out.append(f'<p>Scene <code>{esc(d.get("scene"))}</code>: {fnum(d.get("particles"))} '
               f'particles, {fnum(d.get("bonds"))} bonds, {d.get("steps")} Verlet steps, '
               f'{d.get("rounds")} round(s) alternating the rank counts. Probes and energies '
               f'bitwise identical across rank counts: <b>{"yes" if same else "NO"}</b>. Load '
               f'average after the stage {esc(d.get("loadavg"))}.</p>')
    rows = []
    for c in d.get("per_ranks", []):
        rows.append([str(c["ranks"]), num_td(fnum(c["median_solve_seconds"], 3)),
                     num_td(f'{c["speedup"]:.2f}×'),
                     esc(", ".join(f"{x:.1f}" for x in c["load_before"])),
                     num_td(fnum(c.get("setup_seconds"), 3)),
                     esc(" / ".join(fnum(x) for x in c["owned_particles"])),
                     esc(" / ".join(fnum(x) for x in c["halo_particles"])),
                     esc(" / ".join(f"{x / MIB:.0f}" for x in c["memory_bytes"])),
                     esc(" / ".join(f"{x / MIB:.0f}" for x in c["peak_memory_bytes"])),
                     esc(" / ".join(f"{x / 1024:.0f}" for x in c["halo_bytes_per_step"])),
                     esc(" / ".join(f"{x:.3f}" for x in c.get("halo_exchange_seconds", [])))])
    out.append(table(["ranks", "median solve (s)", "speed-up", "load before each run",
                      "set-up (s)", "particles per rank", "halo per rank", "model MiB per rank",
                      "peak MiB per rank", "halo KiB sent per step, per rank",
                      "time in the exchange (s), per rank"],
                     rows, 'id="mpi-table"'))
    out.append('<p class="note">Model MiB is what a rank keeps for the run (its particles, halo '
               'and bond rows). The peak is set up: every rank still builds the whole model before '
               'keeping its part, so the peak does not fall with the rank count &mdash; the first '
               'thing to distribute before runs beyond one machine\'s memory.</p>')
    per = d.get("per_ranks", [])
    if per:
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9.6, 3.4))
        ranks = [c["ranks"] for c in per]
        ax1.plot(ranks, ranks, "--", color="#999", label="ideal")
        ax1.plot(ranks, [c["speedup"] for c in per], "o-", color="#4a78b5", label="measured")
        ax1.axvline(2, color="#e08a2a", lw=0.8, ls=":", label="cores on this machine")
        ax1.set_xlabel("MPI ranks")
        ax1.set_ylabel("speed-up of the solve")
        ax1.set_xticks(ranks)
        ax1.legend(fontsize=8)
        ax1.grid(alpha=0.3)
        width = 0.35
        xs = range(len(per))
        ax2.bar([x - width / 2 for x in xs], [max(c["memory_bytes"]) / MIB for c in per], width,
                label="model, largest rank", color="#4a78b5")
        ax2.bar([x + width / 2 for x in xs], [max(c["peak_memory_bytes"]) / MIB for c in per], width,
                label="peak resident, largest rank", color="#e08a2a")
        ax2.set_xticks(list(xs), [str(r) for r in ranks])
        ax2.set_xlabel("MPI ranks")
        ax2.set_ylabel("MiB per rank")
        ax2.legend(fontsize=8)
        ax2.grid(alpha=0.3, axis="y")
        fig.tight_layout()
        out.append(f'<img src="{page.savefig(fig, "mpi-scaling.png")}" alt="MPI speed-up and memory">')
    out.append("</section>")
    return "\n".join(out)
