#!/usr/bin/python3
"""MPI strong scaling of libpd on Model C (issue 20): solve time, memory and halo per rank.

    scaling.py PD [--ranks 1,2,4] [--rounds 3] [--scene reports/mpi/model-c-scaling.yaml]
               [--mpiexec "mpiexec --oversubscribe"] [--work DIR] [--json]

Runs `pd run SCENE --threads 1` on each rank count in turn, round after round (1, 2, 4, 1, 2, 4,
…), so that every rank count sees the same stretch of machine load, and records the load average
before each run. Open MPI is told to yield while a rank waits (OMPI_MCA_mpi_yield_when_idle=1),
as it does by itself when oversubscribed. Per rank count it reports the median solve time (summary.json wall_seconds:
the time steps, without set-up), the speed-up against one rank from the medians, and from the
last run the particles, halo copies, model bytes, peak resident bytes and halo bytes sent per
step of each rank. It also checks that every run's probes and energies are bitwise those of the
one-rank run. With --json the whole record is printed as one JSON object (the report's `mpi`
stage); otherwise a table.
"""
from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def loadavg() -> float:
    return float(Path("/proc/loadavg").read_text().split()[0])


def run(pd: str, mpiexec: str, n: int, scene: Path, out: Path) -> dict:
    cmd = shlex.split(mpiexec)
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    cmd += ["-np", str(n), pd, "run", str(scene), "-o", str(out), "--threads", "1", "--overwrite"]
    load = loadavg()
    t0 = time.monotonic()
    # A rank waiting for its neighbour yields the core instead of spinning: on a shared machine
    # a spinning rank takes the time of the other programs, and then of the other rank.
    env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_MCA_mpi_yield_when_idle="1")
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.monotonic() - t0
    if p.returncode != 0:
        sys.exit(f"{shlex.join(cmd)} failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    s = json.loads((out / "summary.json").read_text())
    return {"ranks": n, "load_before": load, "process_seconds": wall,
            "solve_seconds": s["wall_seconds"], "setup_seconds": s.get("setup_seconds"),
            "summary": s}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("pd")
    ap.add_argument("--ranks", default="1,2,4")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--scene", default=str(ROOT / "reports/mpi/model-c-scaling.yaml"))
    ap.add_argument("--mpiexec", default="mpiexec --oversubscribe")
    ap.add_argument("--work", default="/tmp/libpd-mpi-scaling")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    counts = [int(c) for c in a.ranks.split(",")]
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    runs = []
    for r in range(a.rounds):
        for n in counts:
            res = run(a.pd, a.mpiexec, n, Path(a.scene), work / f"np{n}")
            res["round"] = r
            runs.append(res)
            if not a.json:
                print(f"round {r + 1}, {n} rank(s): solve {res['solve_seconds']:.2f} s "
                      f"(load {res['load_before']:.2f})", file=sys.stderr)
    first = next(x for x in runs if x["ranks"] == counts[0])["summary"]
    identical = all(x["summary"]["probes"] == first["probes"] and
                    x["summary"]["kinetic_energy"] == first["kinetic_energy"] and
                    x["summary"]["strain_energy"] == first["strain_energy"] for x in runs)
    per_count = []
    base = None
    for n in counts:
        mine = [x for x in runs if x["ranks"] == n]
        med = statistics.median(x["solve_seconds"] for x in mine)
        base = med if base is None else base
        last = mine[-1]["summary"]
        d = last.get("distribution", {})
        per_count.append({
            "ranks": n, "solve_seconds": [x["solve_seconds"] for x in mine],
            "median_solve_seconds": med, "speedup": base / med,
            "load_before": [x["load_before"] for x in mine],
            "setup_seconds": statistics.median(x["setup_seconds"] for x in mine),
            "owned_particles": d.get("owned_particles", [last["particles"]]),
            "halo_particles": d.get("halo_particles", [0]),
            "cut_bonds": d.get("cut_bonds", 0),
            "memory_bytes": d.get("memory_bytes", [last["memory_bytes"]]),
            "peak_memory_bytes": d.get("peak_memory_bytes", [last["peak_memory_bytes"]]),
            "halo_bytes_per_step": d.get("halo_bytes_per_step", [0]),
            "halo_exchange_seconds": d.get("halo_exchange_seconds", [0]),
        })
    record = {"scene": str(Path(a.scene).resolve().relative_to(ROOT)),
              "particles": first["particles"], "bonds": first["bonds"], "steps": first["steps"],
              "rounds": a.rounds, "bitwise_identical": identical, "per_ranks": per_count}
    if a.json:
        print(json.dumps(record))
    else:
        print(f"{record['scene']}: {record['particles']} particles, {record['bonds']} bonds, "
              f"{record['steps']} steps; probes and energies identical across rank counts: "
              f"{identical}")
        print("ranks | median solve [s] | speed-up | loads | owned per rank | halo per rank | "
              "model MiB per rank | peak MiB per rank | halo KiB/step per rank | "
              "exchange s per rank")
        for c in per_count:
            print(f"{c['ranks']} | {c['median_solve_seconds']:.2f} | {c['speedup']:.2f} | "
                  f"{', '.join(f'{x:.1f}' for x in c['load_before'])} | {c['owned_particles']} | "
                  f"{c['halo_particles']} | "
                  f"{[round(b / 2**20) for b in c['memory_bytes']]} | "
                  f"{[round(b / 2**20) for b in c['peak_memory_bytes']]} | "
                  f"{[round(b / 1024, 1) for b in c['halo_bytes_per_step']]} | "
                  f"{[round(s, 3) for s in c['halo_exchange_seconds']]}")
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
