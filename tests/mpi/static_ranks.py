#!/usr/bin/python3
"""The static solver split over MPI ranks gives the serial solve's displacements.

    static_ranks.py PD MPIEXEC SCENE WORKDIR N1,N2,... [TOLERANCE]

Runs SCENE (solver.integrator: static) in one process without mpiexec (CHOLMOD), then under
MPIEXEC on each rank count N (N = 1 is the serial path again; N > 1 is PETSc's CG + GAMG,
libpd/src/time/distributed_solve.hpp). Every particle's displacement (the last VTU frame, joined
on global_id) must agree with the serial one: max |u_N − u_serial| / max |u_serial| ≤ TOLERANCE
(1e-8). The first split rank count is run twice and must give the same bits both times (a solve
is deterministic for a given rank count). Prints the error, the iterations and times per run.
"""
import json
import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from compare_runs import frame, frames  # noqa: E402
from mpi_test import fail, launcher  # noqa: E402


def run(cmd, out):
    cmd = [*cmd, "run", SCENE, "-o", str(out), "--threads", "1"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=900,
                       env=dict(os.environ, OMP_NUM_THREADS="1"))
    if p.returncode != 0:
        fail(f"{' '.join(cmd)} exited with {p.returncode}:\n{p.stdout}\n{p.stderr}")
    summary = json.loads((out / "summary.json").read_text())
    last = frames(out)[-1][1]
    u = {g: [float(v) for v in row["displacement"].split()] for g, row in frame(last).items()}
    return summary, u


def relative_difference(u, ref):
    if u.keys() != ref.keys():
        fail("the runs wrote different particles")
    scale = max(abs(c) for v in ref.values() for c in v)
    worst = max(abs(a - b) for g in ref for a, b in zip(u[g], ref[g]))
    return worst / scale


def describe(summary):
    d = summary.get("integrator_details", {})
    return (f"{d.get('unknowns')} unknowns, {d.get('solver')}, Newton {d.get('newton_iterations')}"
            f", residual {d.get('residual'):.3g}; set-up {summary.get('setup_seconds', 0):.1f} s"
            f", solve {summary.get('solve_seconds', 0):.1f} s")


def main():
    global SCENE
    if len(sys.argv) not in (6, 7):
        fail(__doc__)
    pd, mpiexec, SCENE, work, counts = sys.argv[1:6]
    tolerance = float(sys.argv[6]) if len(sys.argv) == 7 else 1e-8
    work = Path(work)
    subprocess.run(["rm", "-rf", str(work)], check=True)
    work.mkdir(parents=True)
    serial, ref = run([pd], work / "serial")
    print(f"serial: {describe(serial)}")
    repeated = False
    for n in [int(c) for c in counts.split(",")]:
        summary, u = run([*launcher(mpiexec, n), pd], work / f"np{n}")
        error = relative_difference(u, ref)
        print(f"{n} rank(s): max |u - u_serial| / max |u_serial| = {error:.3e}; {describe(summary)}")
        if not error <= tolerance:
            fail(f"{n} ranks differ from the serial solve by {error:.3e} > {tolerance:g}")
        if n > 1 and not repeated:
            repeated = True
            _, again = run([*launcher(mpiexec, n), pd], work / f"np{n}-again")
            if again != u:
                fail(f"two runs on {n} ranks differ (by {relative_difference(again, u):.3e})")
            print(f"{n} ranks, run again: bitwise identical displacements")
    print("PASS")


SCENE = ""

if __name__ == "__main__":
    main()
