#!/usr/bin/env python3
"""Issue 15's acceptance measurement: the static solver against dynamic relaxation (ADR) on the
structural scenes, each run `pd run SCENE --threads 1` without VTU, the two (or three, with
--before) alternating within every round, so that both see the same machine. Prints the medians
(static and ADR solve phase, their ratio, the whole run, peak memory), the probes' relative
difference and the load averages at the runs' starts, and where the static solve phase went.

    python3 tools/static_vs_adr.py build/bin/pd [--rounds 3] [--before OLD_PD]
        [--scenes clamped-beam,cantilever,plate-3clamped] [--json rows.json]

The machines are shared: quote the load averages with the ratios; the ratios of one run are what
the acceptance compares. Standard library only.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "verification" / "scenes"
PHASES = ["symmetry_check_seconds", "assembly_seconds", "factorisation_seconds", "analysis_seconds",
          "newton_seconds", "newton_iterations"]


def scene_copy(name: str, integrator: str, folder: Path) -> Path:
    """The scene with `integrator` and without VTU output."""
    text = (SCENES / f"{name}.yaml").read_text()
    text, n = re.subn(r"^(  integrator:) *[\w-]+", rf"\1 {integrator}", text, flags=re.M)
    if n != 1:
        sys.exit(f"{name}.yaml: expected one 'integrator:' line in its solver section")
    text = re.sub(r"^(  vtu:) *true", r"\1 false", text, flags=re.M)
    path = folder / f"{name}-{integrator}.yaml"
    path.write_text(text)
    return path


def run(pd: str, scene: Path, out: Path) -> dict:
    load = float(Path("/proc/loadavg").read_text().split()[0])
    env = dict(os.environ, OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive")
    subprocess.run([pd, "run", str(scene), "-o", str(out), "--threads", "1", "--overwrite"], env=env,
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    s = json.loads((out / "summary.json").read_text())
    return dict(load=load, solve=s["solve_seconds"], setup=s["setup_seconds"],
                whole=s["setup"]["scene_seconds"] + s["setup_seconds"] + s["solve_seconds"],
                peak=s["peak_memory_bytes"], probes=s["probes"],
                details=s.get("integrator_details") or {})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("pd")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--before", help="an earlier pd whose static solve runs beside, for its time")
    ap.add_argument("--scenes", default="clamped-beam,cantilever,plate-3clamped")
    ap.add_argument("--json", help="write every run here")
    a = ap.parse_args()
    runs = ([("before", a.before, "static")] if a.before else []) + [("static", a.pd, "static"),
                                                                     ("adr", a.pd, "adr")]
    rows = []
    with tempfile.TemporaryDirectory(prefix="static-vs-adr-") as tmp:
        folder = Path(tmp)
        for r in range(a.rounds):
            for name in a.scenes.split(","):
                for tag, pd, integrator in runs:
                    row = run(pd, scene_copy(name, integrator, folder), folder / f"{name}-{tag}")
                    row.update(round=r, scene=name, tag=tag)
                    rows.append(row)
                    print(f"round {r} {name:16s} {tag:7s} solve {row['solve']:8.3f} s, load "
                          f"{row['load']:.2f}", file=sys.stderr, flush=True)
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1))

    def med(xs, key):
        return statistics.median(x[key] for x in xs)

    print("| scene | static solve | ADR solve | ratio | whole run static / ADR | ratio | peak memory "
          "static / ADR | static vs ADR | load |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in a.scenes.split(","):
        g = {tag: [x for x in rows if x["scene"] == name and x["tag"] == tag] for tag, _, _ in runs}
        st, ad = g["static"], g["adr"]
        before = f"{med(g['before'], 'solve'):.3f} → " if a.before else ""
        diff = ", ".join(f"{k} {abs(v / ad[0]['probes'][k] - 1):.1e}"
                         for k, v in st[0]["probes"].items())
        loads = [x["load"] for x in st + ad]
        print(f"| {name} | {before}{med(st, 'solve'):.3f} s | {med(ad, 'solve'):.2f} s | "
              f"{med(ad, 'solve') / med(st, 'solve'):.1f}× | {med(st, 'whole'):.2f} / "
              f"{med(ad, 'whole'):.2f} s | {med(ad, 'whole') / med(st, 'whole'):.1f}× | "
              f"{med(st, 'peak') / 2**20:.0f} / {med(ad, 'peak') / 2**20:.0f} MiB | {diff} | "
              f"{min(loads):.1f}–{max(loads):.1f} |")
    print()
    for name in a.scenes.split(","):
        for tag in ["before", "static"] if a.before else ["static"]:
            xs = [x for x in rows if x["scene"] == name and x["tag"] == tag]
            phases = ", ".join(f"{k.replace('_seconds', '')} {med_detail(xs, k):.3g}" for k in PHASES)
            d = xs[0]["details"]
            print(f"{name} {tag}: {phases}; set-up {med(xs, 'setup'):.3f} s; "
                  f"{d.get('solver', '?')}, factor {d.get('factor_bytes', 0) / 2**20:.0f} MiB")


def med_detail(xs, key):
    values = [x["details"][key] for x in xs if key in x["details"]]
    return statistics.median(values) if values else float("nan")


if __name__ == "__main__":
    main()
