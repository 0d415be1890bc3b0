#!/usr/bin/env python3
"""libpd verification report: one command, one HTML page (accuracy, cost, stability).

    python3 reports/pd_report.py [-o DIR] [--full] [--build-dir build]
    python3 reports/pd_report.py --compare OLD.json [NEW.json]      # CI diff, exit 1 on regression
    python3 reports/pd_report.py --render-only --data DIR -o DIR2   # re-render stored stage data

Stages (each cached under DIR/cache/ by a hash of its inputs; see reports/README.md):
  fem:*        deal.II references: the gold files are used, and `pd-fem PRM --coarse --check GOLD`
               proves the current pd-fem still reproduces them (--full: the full pd-fem run).
  verify:*     `pd verify CASE` for every case of `pd verify --list`.
  scene:*      `pd verify SCENE.yaml --fe-coarse` for every elastic scene of verification/scenes/user/.
  mpi          reports/mpi/scaling.py: Model C on 1, 2 and 4 MPI ranks (speed-up, memory, halo).
  sweep:*      `pd verify --sweep CASE` (accuracy vs time).
  stability    `pd stability SCENE... --json`.
  compare:*    `pd compare dynamic|quasistatic -o FILE.jsonl`.
  bench        `pd bench model-a-benchmark.yaml --stretch X --threads N --json`.
  kernel       `pd-kernel-bench --benchmark_format=json`.
  peer         `pd bench model-a-benchmark.yaml --lammps lmp --json`: libpd/LAMMPS alternated.
  lammps       `bash reports/lammps/run_lammps_bench.sh`.
  fibre-bench  `pd bench SCENE --bond-model M --json`: the virtual-fibre and bond-based kernels alternated.
  threads-under-load  the clamped beam, the plate and Model A on the default threads and on one,
               beside one busy process per core (started and killed by the stage).
  mesh-setup   (--full) `pd run verification/scenes/benchmarks/mesh-body-benchmark.yaml`: set-up
               time and memory of a CAD part meshed by Gmsh and filled with about a million
               lattice sites.
Output: DIR/index.html, DIR/*.png, DIR/report.json, DIR/data/*.json (stage records).
Exit code: 0 all stages ran and all gates passed, 2 a verification gate failed, 1 a stage failed.
"""
from __future__ import annotations

import os
import sys

# Debian's python3-matplotlib lives in /usr/bin/python3's site-packages; a python3 from pyenv or a
# venv earlier on PATH does not see it.  Re-run with the system interpreter rather than fail.
try:
    if "--compare" not in sys.argv:   # --compare needs neither: keep it fast
        import matplotlib  # noqa: F401
        import yaml  # noqa: F401
except ImportError:
    if os.path.exists("/usr/bin/python3") and os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") \
            and not os.environ.get("PD_REPORT_REEXEC"):
        os.environ["PD_REPORT_REEXEC"] = "1"
        os.execv("/usr/bin/python3", ["/usr/bin/python3", *sys.argv])
    if "--compare" not in sys.argv:
        sys.exit("pd_report.py: error: matplotlib or PyYAML is missing "
                 "(apt-get install python3-matplotlib python3-yaml)")

import argparse  # noqa: E402
import fnmatch  # noqa: E402
import json  # noqa: E402
import shlex  # noqa: E402
import time  # noqa: E402
import traceback  # noqa: E402
from concurrent.futures import ThreadPoolExecutor, as_completed  # noqa: E402
from pathlib import Path  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from pdreport import cases as case_files  # noqa: E402
from pdreport import compare as cmp  # noqa: E402
from pdreport import stages as S  # noqa: E402
from pdreport import timing  # noqa: E402
from pdreport.mesh_setup import mesh_setup_stage  # noqa: E402
from pdreport.threads_under_load import threads_under_load_stage  # noqa: E402

ROOT = HERE.parent

# What the default report runs (≤ 6 min fresh on 2 cores, issue 15) and what --full adds (≤ 60
# min). The default report sweeps the three structures with their case files' `quick_sweep:`
# lists (`pd verify --sweep --quick`); --full runs every case file's complete `sweep:`.
DEFAULT_SWEEP_CASES = ["clamped-beam", "cantilever", "plate-3clamped"]
DEFAULT_STABILITY_SCENES = ["bar-vibration/bar-vibration.yaml"]
FULL_STABILITY_SCENES = ["bar-vibration/bar-vibration.yaml", "clamped-beam/clamped-beam.yaml",
                         "plate-3clamped/plate-3clamped.yaml"]   # in verification/cases
# One ARKode table per order (2 to 5), one of them with β = 0 (Heun–Euler) and one measured past
# β (Dormand–Prince): the 6- and 7-stage Cash–Karp and Fehlberg alone took 20 of the stage's 49 s.
# --full measures every table.
DEFAULT_STABILITY_INTEGRATORS = ["verlet", "arkode:heun-euler", "arkode:bogacki-shampine", "arkode:rk4",
                                 "arkode:dormand-prince"]


CASES: list[list[str]] = []   # [name, summary] of `pd verify --list`


def fmt_s(s: float) -> str:
    s = max(0, int(round(s)))
    return f"{s // 60}:{s % 60:02d}"


def build_stages(ctx: S.Ctx, records: dict[str, dict]) -> list[S.Stage]:
    t0 = time.time()
    try:
        cases = S.list_cases(ctx)
    except S.StageFailed as e:
        records["verify:list"] = {"name": "verify:list", "group": "verify", "title": "pd verify --list",
                                  "status": "failed", "error": str(e), "seconds": time.time() - t0,
                                  "cached": False, "commands": [[str(ctx.pd), "verify", "--list"]],
                                  "result": None}
        cases = []
    CASES[:] = [list(c) for c in cases]
    listed = {c for c, _ in cases}
    structures = case_files.load()
    order = case_files.in_listed_order(structures, [c for c, _ in cases])
    # The deal.II checks of the references the report compares with: in the default mode not
    # those whose only cases are "(slow)" (plate-thin's coarse check took 48 CPU-s for a case the
    # default report does not run).
    runs = {c for c, summary in cases if ctx.full or "(slow)" not in summary}
    compared = [c for c in order if ctx.full or c in DEFAULT_SWEEP_CASES or {c, f"{c}-fast"} & runs]
    stages: list[S.Stage] = [S.fem_stage(ctx, p, cs) for p, cs in S.fe_problems(structures, compared).items()]
    # `CASE-sweep` cases are the accuracy-vs-time sweeps: they go to the sweep stages.
    # Cases that `pd verify --list` itself calls "(slow)" run only with --full; the summary table
    # lists them as not run, with the reason.
    stages += [S.verify_stage(ctx, c, summary) for c, summary in cases
               if not c.endswith("-sweep") and (ctx.full or "(slow)" not in summary)]
    stages += [S.scene_stage(ctx, p) for p in S.user_scenes(ctx)]
    sweep_cases = [c for c in order if structures[c].has_sweep] if ctx.full else DEFAULT_SWEEP_CASES
    stages += [S.sweep_stage(ctx, c, listed) for c in sweep_cases]
    stages.append(S.stability_stage(ctx, FULL_STABILITY_SCENES, []) if ctx.full
                  else S.stability_stage(ctx, DEFAULT_STABILITY_SCENES, DEFAULT_STABILITY_INTEGRATORS))
    stages += [S.compare_stage(ctx, "dynamic"), S.compare_stage(ctx, "quasistatic")]
    stages += [S.bench_stage(ctx), S.kernel_stage(ctx), S.peer_stage(ctx)]
    if ctx.full:  # LAMMPS's own thread scan; `peer` measures the ratio in every report
        stages.append(S.lammps_stage(ctx))
    stages.append(S.fibre_bench_stage(ctx))
    stages.append(threads_under_load_stage(ctx))
    if ctx.full:  # a million-particle CAD part: a minute or more
        stages.append(mesh_setup_stage(ctx))
    stages.append(S.mpi_stage(ctx))
    return stages


def load_json(p: Path, default: object) -> object:
    try:
        return json.loads(p.read_text())
    except (OSError, json.JSONDecodeError):
        return default


def write_json(p: Path, obj: object) -> None:
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_suffix(p.suffix + ".tmp")
    tmp.write_text(json.dumps(obj, indent=1, default=str))
    os.replace(tmp, p)


def cached_records(cache: Path, stages: list[S.Stage], keys: dict[str, str],
                   force: list[str]) -> dict[str, dict]:
    """The stored records still valid: same key, status ok, and not forced to rerun."""
    cached: dict[str, dict] = {}
    for st in stages:
        c = load_json(cache / f"{st.file_name}.json", None)
        if (isinstance(c, dict) and c.get("key") == keys[st.name] and c.get("status") == "ok"
                and not any(fnmatch.fnmatch(st.name, f) for f in force)):
            cached[st.name] = c
    return cached


def execute_stage(ctx: S.Ctx, st: S.Stage, key: str) -> dict:
    """Runs one stage; its record, with the error of a stage that failed."""
    t0 = time.time()
    S.cpu_account_reset()
    rec = {"name": st.name, "group": st.group, "title": st.title, "key": key,
           "commands": st.commands, "cached": False,
           "threads": int(st.env.get("OMP_NUM_THREADS", os.cpu_count() or 1)),
           "loadavg_at_start": os.getloadavg()[0]}
    try:
        rec["result"] = st.fn(ctx, st)
        rec["status"] = "ok"
        rec["error"] = None
    except S.StageFailed as e:
        rec["status"], rec["error"], rec["result"] = "failed", str(e), None
    except Exception as e:  # a bug in the stage code: still show it, never hide it
        rec["status"], rec["result"] = "failed", None
        rec["error"] = f"{type(e).__name__}: {e}\n{traceback.format_exc(limit=4)}"
    rec["seconds"] = time.time() - t0
    rec["cpu_seconds"] = S.cpu_account()
    return rec


def next_batch(stages: list[S.Stage], i: int, jobs: int) -> list[S.Stage]:
    """Stage i and, if it may share the machine and jobs > 1, the parallel stages after it."""
    batch = [stages[i]]
    if stages[i].parallel and jobs > 1:
        while i + len(batch) < len(stages) and stages[i + len(batch)].parallel:
            batch.append(stages[i + len(batch)])
    return batch


def keep_stage_order(stages: list[S.Stage], records: dict[str, dict]) -> None:
    """Reorders records in place: the stage order of the list, not the completion order."""
    order = [st.name for st in stages]
    ordered = {n: records[n] for n in order if n in records}
    for n in list(records):
        if n not in ordered:
            ordered[n] = records[n]
    records.clear()
    records.update(ordered)


def run_stages(ctx: S.Ctx, stages: list[S.Stage], records: dict[str, dict], force: list[str],
               jobs: int) -> list[S.Stage]:
    """Runs (or takes from the cache) every stage; returns the stages it ran, in the order it
    started them."""
    cache = ctx.out / "cache"
    data = ctx.out / "data"
    cache.mkdir(parents=True, exist_ok=True)
    data.mkdir(parents=True, exist_ok=True)
    durations: dict[str, float] = load_json(cache / "durations.json", {})  # type: ignore[assignment]
    keys = {st.name: S.stage_key(ctx, st) for st in stages}
    cached = cached_records(cache, stages, keys, force)
    estimate = {st.name: 0.0 if st.name in cached else durations.get(st.name, st.default_seconds)
                for st in stages}
    total_est = sum(estimate.values())
    n_cached = len(cached)
    print(f"== libpd report: {len(stages)} stages ({n_cached} cached), estimated {fmt_s(total_est)} "
          f"(m:ss; from the previous run's durations where recorded) -> {ctx.out}", flush=True)
    start = time.time()
    done_est = 0.0
    submitted: list[S.Stage] = []

    def execute(st: S.Stage) -> dict:
        return execute_stage(ctx, st, keys[st.name])

    def finish(i: int, st: S.Stage, rec: dict) -> None:
        nonlocal done_est
        done_est += estimate[st.name]
        if not rec.get("cached"):
            durations[st.name] = rec["seconds"]
            write_json(cache / "durations.json", durations)
            if rec["status"] == "ok":
                write_json(cache / f"{st.file_name}.json", rec)
            mark = "ok" if rec["status"] == "ok" else "FAILED"
            print(f"[{i:>2}/{len(stages)}] {st.name:<28} {mark} in {rec['seconds']:.1f} s "
                  f"({rec['cpu_seconds']:.1f} s CPU)" +
                  ("" if rec["status"] == "ok" else ": " + " | ".join(l for l in rec["error"].splitlines()[:3] if l.strip())[:300]) +
                  f"  (elapsed {fmt_s(time.time() - start)}, ETA {fmt_s(max(total_est - done_est, 0))})",
                  flush=True)
        records[st.name] = rec
        write_json(data / f"{st.file_name}.json", rec)

    # Consecutive stages that may share the machine (the verification cases: most models are
    # below libpd's 4096-particle threshold and run on one core) run `jobs` at a time, each with
    # OMP_NUM_THREADS = cores / jobs; everything else (FE, benchmarks, ...) runs alone.
    i = 0
    while i < len(stages):
        batch = next_batch(stages, i, jobs)
        for k, st in enumerate(batch):
            if st.name in cached:
                rec = dict(cached[st.name])
                rec["cached"] = True
                print(f"[{i + k + 1:>2}/{len(stages)}] {st.name:<28} cached ({rec.get('seconds', 0):.1f} s when run)",
                      flush=True)
                finish(i + k + 1, st, rec)
        todo = [(i + k + 1, st) for k, st in enumerate(batch) if st.name not in cached]
        submitted.extend(st for _, st in sorted(todo, key=lambda t: -estimate[t[1].name]))
        if len(todo) == 1 or (todo and jobs <= 1):
            for n, st in todo:
                print(f"[{n:>2}/{len(stages)}] {st.name:<28} running, est. {fmt_s(estimate[st.name])}, "
                      f"ETA {fmt_s(max(total_est - done_est, 0))}", flush=True)
                finish(n, st, execute(st))
        elif todo:
            # Longest first (from the previous run's durations, else the stages' guesses): a long
            # stage started last would leave the other core idle at the end of the batch.
            todo.sort(key=lambda t: -estimate[t[1].name])
            threads = max(1, (os.cpu_count() or 1) // jobs)
            for _, st in todo:
                st.env.setdefault("OMP_NUM_THREADS", str(threads))
            print(f"        {len(todo)} stages {todo[0][1].group}:* , {jobs} at a time "
                  f"(OMP_NUM_THREADS={threads}), est. {fmt_s(sum(estimate[s.name] for _, s in todo) / jobs)}",
                  flush=True)
            with ThreadPoolExecutor(max_workers=jobs) as pool:
                futs = {pool.submit(execute, st): (n, st) for n, st in todo}
                for f in as_completed(futs):
                    n, st = futs[f]
                    finish(n, st, f.result())
        i += len(batch)
    keep_stage_order(stages, records)
    return submitted


def load_records(data: Path) -> tuple[dict[str, dict], dict, dict]:
    records: dict[str, dict] = {}
    for f in sorted(data.glob("*.json")):
        if f.stem.startswith("_"):
            continue
        r = load_json(f, None)
        if isinstance(r, dict) and "name" in r:
            records[r["name"]] = r
    order = load_json(data / "_order.json", [])
    if isinstance(order, list) and order:
        records = {n: records[n] for n in order if n in records} | {
            n: r for n, r in records.items() if n not in order}
    env = load_json(data / "_environment.json", {})
    meta = load_json(data / "_meta.json", {})
    return records, env, meta  # type: ignore[return-value]


def argument_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", default="out/report", help="report directory (default out/report)")
    ap.add_argument("--full", action="store_true", help="complete sweeps, full FE runs, more stability scenes (≤ 60 min)")
    ap.add_argument("--build-dir", default="build", help="CMake build directory with bin/pd (default build)")
    ap.add_argument("--compare", nargs="+", metavar="JSON",
                    help="OLD.json [NEW.json]: list regressions beyond noise (NEW defaults to DIR/report.json)")
    ap.add_argument("--render-only", action="store_true", help="do not run stages; render stored stage data")
    ap.add_argument("--data", help="with --render-only: folder of stage records (default DIR/data)")
    ap.add_argument("--only", action="append", default=[], metavar="GLOB",
                    help="run only stages whose name matches (e.g. 'verify:*'); repeatable")
    ap.add_argument("--force", action="append", default=[], metavar="GLOB",
                    help="rerun matching stages even if cached; repeatable ('*' = everything)")
    ap.add_argument("-j", "--jobs", type=int, default=os.cpu_count() or 1,
                    help="verification cases run this many at a time (default: cores)")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every command")
    return ap


def render_only(ap: argparse.ArgumentParser, a: argparse.Namespace, out: Path) -> int:
    """--render-only: the page from stored stage records, without running a stage."""
    from pdreport import render as R  # matplotlib only needed from here on

    data = Path(a.data) if a.data else out / "data"
    if not data.is_dir():
        ap.error(f"--render-only: {data} is not a folder of stage records")
    records, env, meta = load_records(data)
    if not records:
        ap.error(f"--render-only: no stage records in {data}")
    meta = dict(meta or {})
    meta["rendered_from"] = str(data)
    R.render(out, records, env, meta)
    print(f"rendered {len(records)} stage records -> {out / 'index.html'}")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argument_parser()
    a = ap.parse_args(argv)

    out = Path(a.output)
    if a.compare:
        if len(a.compare) > 2:
            ap.error("--compare takes OLD.json [NEW.json]")
        new = a.compare[1] if len(a.compare) == 2 else str(out / "report.json")
        return cmp.main(a.compare[0], new)

    if a.render_only:
        return render_only(ap, a, out)
    from pdreport import render as R  # matplotlib only needed from here on

    build = Path(a.build_dir)
    if not build.is_absolute():
        build = (Path.cwd() / build) if (Path.cwd() / build).exists() else ROOT / build
    out = out if out.is_absolute() else Path.cwd() / out
    ctx = S.Ctx(root=ROOT, build=build.resolve(), out=out.resolve(), full=a.full, verbose=a.verbose)
    ctx.out.mkdir(parents=True, exist_ok=True)
    env = S.environment(ctx)
    write_json(ctx.out / "data" / "_environment.json", env)   # so a partial --render-only has it
    records: dict[str, dict] = {}
    t0 = time.time()
    stages = build_stages(ctx, records)
    if a.only:
        # Run only the selected stages; keep the stored records of the others for the page.
        previous, _, _ = load_records(ctx.out / "data")
        stages = [s for s in stages if any(fnmatch.fnmatch(s.name, g) for g in a.only)]
        ran = run_stages(ctx, stages, records, a.force, a.jobs)
        records = previous | records
    else:
        ran = run_stages(ctx, stages, records, a.force, a.jobs)
        # Records of stages that no longer exist must not leak into a later --render-only.
        names = {S.safe_name(n) for n in records}
        for f in (ctx.out / "data").glob("*.json"):
            if f.stem not in names and not f.stem.startswith("_"):
                f.unlink()
    total = time.time() - t0
    meta = {"mode": "full (--full)" if a.full else "default",
            "command": "python3 reports/pd_report.py " + shlex.join(sys.argv[1:] if argv is None else argv),
            "total_seconds": total,
            "stage_seconds": {n: r.get("seconds") for n, r in records.items()},
            "stage_cpu_seconds": {n: r.get("cpu_seconds") for n, r in records.items()},
            "loadavg_at_end": list(os.getloadavg()),
            "quiet_estimate": timing.quiet_estimate(
                [(st.name, st.parallel, records[st.name].get("cpu_seconds") or 0.0) for st in ran],
                a.jobs, os.cpu_count() or 1),
            "stage_cached": {n: bool(r.get("cached")) for n, r in records.items()},
            "cases": CASES, "case_metadata": list(S.CASE_METADATA.values())}
    data = ctx.out / "data"
    write_json(data / "_environment.json", env)
    write_json(data / "_meta.json", meta)
    write_json(data / "_order.json", list(records))
    if "verify:list" in records:
        write_json(data / "verify_list.json", records["verify:list"])
    R.render(ctx.out, records, env, meta)
    failed = [n for n, r in records.items() if r.get("status") != "ok"]
    gates = [n for n, r in records.items() if r.get("group") == "verify" and r.get("status") == "ok"
             and not (r.get("result") or {}).get("passed")]
    q = meta["quiet_estimate"]
    print(f"== report: {ctx.out / 'index.html'} and report.json ({fmt_s(total)} this run, "
          f"{q['cpu_seconds']:.0f} CPU s; on a quiet {q['cores']}-core machine an estimated "
          f"{fmt_s(q['low_seconds'])}–{fmt_s(q['high_seconds'])}; load average at the end "
          f"{meta['loadavg_at_end'][0]:.1f})")
    if failed:
        print(f"== {len(failed)} stage(s) FAILED: {', '.join(failed)}")
    if gates:
        print(f"== {len(gates)} verification gate(s) failed: {', '.join(g.split(':', 1)[1] for g in gates)}")
    return 1 if failed else 2 if gates else 0


if __name__ == "__main__":
    sys.exit(main())
