"""The report's threads-under-load stage: the headline runs on pd's default threads and on one,
beside a competing load that the stage starts itself."""
from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
import time
from pathlib import Path

from .stages import BENCH_SCENE, Ctx, Stage, StageFailed, _loadavg, parse_json_output, run

# The thread policy under a competing load: the headline runs with the default threads and with
# `--threads 1`, alternating, beside one busy process per core that the stage starts and always
# kills. The default must not lose to one thread (issue 41: at most 1.1x), and a static result must
# be bitwise the same for both (the probes are compared).
LOAD_SCENES = (("clamped beam (static)", "verification/cases/clamped-beam/clamped-beam.yaml"),
               ("plate (static)", "verification/cases/plate-3clamped/plate-3clamped.yaml"),
               ("Model A (300 force evaluations)", BENCH_SCENE))
LOAD_THREADS = (None, 1)    # None: pd's default


def _busy_processes(n: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"], stdin=subprocess.DEVNULL)
            for _ in range(n)]


def threads_under_load_stage(ctx: Ctx) -> Stage:
    rounds = 5 if ctx.full else 3
    busy = os.cpu_count() or 1

    def cmd(scene: str, threads: int | None) -> list[str]:
        extra = [] if threads is None else ["--threads", str(threads)]
        if scene == BENCH_SCENE:
            return [str(ctx.pd), "bench", str(ctx.root / scene), "--steps", "300", "--repeats", "3",
                    "--json"] + extra
        out = ctx.work / "threads-under-load" / f"{Path(scene).stem}-{threads or 'default'}"
        return [str(ctx.pd), "run", str(ctx.root / scene), "-o", str(out), "--overwrite"] + extra

    cmds = [cmd(scene, t) for _, scene in LOAD_SCENES for t in LOAD_THREADS]

    def timed(scene: str, threads: int | None, log: str) -> dict:
        c = cmd(scene, threads)
        start = time.monotonic()
        p = run(ctx, c, log)
        wall = time.monotonic() - start
        if scene == BENCH_SCENE:
            j = parse_json_output(p.stdout)
            if not isinstance(j, dict) or "seconds" not in j:
                raise StageFailed(f"`{shlex.join(c)}` printed no time")
            return {"seconds": j["seconds"], "threads": j.get("threads")}
        summary = json.loads((Path(c[c.index("-o") + 1]) / "summary.json").read_text())
        return {"seconds": wall, "probes": summary.get("probes")}

    def fn(ctx: Ctx, st: Stage) -> dict:
        runs: dict[str, list[dict]] = {}
        loads = []
        procs = _busy_processes(busy)
        try:
            time.sleep(0.5)  # the competitors are running before the first timing
            for r in range(rounds):
                loads.append(_loadavg())
                for label, scene in LOAD_SCENES:
                    # Alternate which goes first, so that neither always follows the other.
                    for t in (LOAD_THREADS if r % 2 == 0 else LOAD_THREADS[::-1]):
                        key = "default" if t is None else str(t)
                        log = f"threads-under-load-{Path(scene).stem}-{key}-{r}"
                        runs.setdefault(f"{label}|{key}", []).append(timed(scene, t, log))
        finally:
            for p in procs:
                p.kill()
            for p in procs:
                p.wait()
        loads.append(_loadavg())
        out = []
        for label, scene in LOAD_SCENES:
            default, one = runs[f"{label}|default"], runs[f"{label}|1"]
            med = [sorted(x["seconds"] for x in v)[len(v) // 2] for v in (default, one)]
            # The ratio is taken per round, whose two runs saw the same load, then its median.
            ratios = sorted(d["seconds"] / o["seconds"] for d, o in zip(default, one))
            probes = [x.get("probes") for x in default + one]
            out.append({"label": label, "scene": scene, "default_seconds": [x["seconds"] for x in default],
                        "one_thread_seconds": [x["seconds"] for x in one],
                        "default_median": med[0], "one_thread_median": med[1],
                        "ratios": ratios, "ratio": ratios[len(ratios) // 2],
                        "default_threads": default[0].get("threads"),
                        "identical": None if probes[0] is None else all(p == probes[0] for p in probes)})
        return {"rounds": rounds, "busy_processes": busy, "scenes": out, "loadavg": loads}

    return Stage("threads-under-load", "bench",
                 "default threads vs one thread beside a busy process per core", cmds,
                 [ctx.pd] + [ctx.root / s for _, s in LOAD_SCENES], fn,
                 default_seconds=200 if ctx.full else 120)
