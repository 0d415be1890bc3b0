"""The report's stages: each runs one of the C++ tools and returns its JSON.

A stage is cached under DIR/cache/ by a hash of everything it reads: the command line, the
binaries it runs (content hash), and the scene / case / prm / reference files.  A rerun recomputes
only stages whose key changed.  A stage whose command is missing or fails raises StageFailed with
the command and its error output; the driver records that and the page shows it as failed.
"""
from __future__ import annotations

import csv
import hashlib
import json
import os
import re
import shlex
import shutil
import subprocess
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from .cases import Case


class StageFailed(Exception):
    """A stage could not produce its data; the message is shown in the page."""


@dataclass
class Ctx:
    root: Path                  # repository root
    build: Path                 # build directory (binaries in build/bin)
    out: Path                   # report directory
    full: bool = False
    verbose: bool = False

    @property
    def bin(self) -> Path:
        return self.build / "bin"

    @property
    def pd(self) -> Path:
        return self.bin / "pd"

    @property
    def work(self) -> Path:
        return self.out / "cache" / "work"

    def rel(self, p: Path | str) -> str:
        try:
            return str(Path(p).resolve().relative_to(self.root.resolve()))
        except ValueError:
            return str(p)


@dataclass
class Stage:
    name: str                                   # unique, e.g. "verify:clamped-beam"
    group: str                                  # fem, verify, sweep, stability, compare, bench, kernel, lammps
    title: str
    commands: list[list[str]]                   # what runs (shown in the page, part of the key)
    inputs: list[Path]                          # files whose content is part of the key
    fn: Callable[["Ctx", "Stage"], dict]
    default_seconds: float                      # ETA guess when no previous run recorded one
    env: dict[str, str] = field(default_factory=dict)
    parallel: bool = False                      # may run beside other parallel stages

    @property
    def file_name(self) -> str:
        return safe_name(self.name)


def safe_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name)


# ---- helpers -----------------------------------------------------------------------------------

_hash_memo: dict[tuple[str, float, int], str] = {}


def file_hash(p: Path) -> str:
    try:
        st = p.stat()
    except OSError:
        return "missing"
    memo = (str(p), st.st_mtime, st.st_size)
    if memo not in _hash_memo:
        h = hashlib.sha256()
        with open(p, "rb") as f:
            for chunk in iter(lambda: f.read(1 << 20), b""):
                h.update(chunk)
        _hash_memo[memo] = h.hexdigest()
    return _hash_memo[memo]


def stage_key(ctx: Ctx, stage: Stage) -> str:
    h = hashlib.sha256()
    payload = {
        "name": stage.name,
        "full": ctx.full,
        "commands": [[_neutral(ctx, a) for a in c] for c in stage.commands],
        "env": {k: v for k, v in stage.env.items() if k != "OMP_NUM_THREADS"},  # results do not depend on it
        "inputs": sorted((ctx.rel(p), file_hash(p)) for p in stage.inputs),
    }
    h.update(json.dumps(payload, sort_keys=True).encode())
    return h.hexdigest()[:20]


def _neutral(ctx: Ctx, arg: str) -> str:
    """Command arguments without the report directory, so moving -o keeps keys stable."""
    return arg.replace(str(ctx.out), "$DIR").replace(str(ctx.root), "$ROOT")


# CPU seconds (user + sys) of the commands a stage ran, summed per thread: each stage runs in its
# own worker thread, so the driver reads its stage's account after the stage's function returns.
# With the wall time this lets a run on a loaded machine say what the stages cost in CPU.
_cpu = threading.local()


def cpu_account_reset() -> None:
    _cpu.seconds = 0.0


def cpu_account() -> float:
    return getattr(_cpu, "seconds", 0.0)


def run(ctx: Ctx, cmd: list[str], log_name: str, ok: tuple[int, ...] = (0,),
        env: dict[str, str] | None = None, timeout: float | None = None,
        cwd: Path | None = None) -> subprocess.CompletedProcess:
    exe = cmd[0]
    if os.sep in exe:
        if not Path(exe).exists():
            raise StageFailed(f"{exe} not found — build it first (ninja -C {ctx.rel(ctx.build)})")
    elif shutil.which(exe) is None:
        raise StageFailed(f"command '{exe}' not found on PATH")
    logs = ctx.work / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    full_env = dict(os.environ)
    full_env.update(env or {})
    if ctx.verbose:
        print("    $ " + shlex.join(cmd), flush=True)
    out_log, err_log = logs / f"{log_name}.stdout", logs / f"{log_name}.stderr"
    # The output goes to the log files and the child is reaped with wait4, whose rusage is this
    # command's CPU time (with its own waited-for children: mpiexec's ranks, pd-fem under pd).
    with open(out_log, "w") as fo, open(err_log, "w") as fe:
        proc = subprocess.Popen(cmd, stdout=fo, stderr=fe, text=True, env=full_env,
                                cwd=str(cwd or ctx.root))
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            pid, status, usage = os.wait4(proc.pid, 0 if deadline is None else os.WNOHANG)
            if pid:
                break
            if time.monotonic() > deadline:  # type: ignore[operator]
                proc.kill()
                os.wait4(proc.pid, 0)
                proc.returncode = -9
                raise StageFailed(f"`{shlex.join(cmd)}` did not finish within {timeout:.0f} s")
            time.sleep(0.05)
    proc.returncode = os.waitstatus_to_exitcode(status)
    _cpu.seconds = cpu_account() + usage.ru_utime + usage.ru_stime
    p = subprocess.CompletedProcess(cmd, proc.returncode, out_log.read_text(errors="replace"),
                                    err_log.read_text(errors="replace"))
    if p.returncode not in ok:
        tail = (p.stderr.strip() or p.stdout.strip())[-2000:]
        raise StageFailed(f"`{shlex.join(cmd)}` exited with code {p.returncode}:\n{tail}")
    return p


def pd_help(ctx: Ctx, *sub: str) -> str:
    """`pd [SUB] --help` text ('' if pd is missing)."""
    if not ctx.pd.exists():
        return ""
    p = subprocess.run([str(ctx.pd), *sub, "--help"], capture_output=True, text=True)
    return p.stdout + p.stderr


def require_subcommand(ctx: Ctx, name: str) -> None:
    text = pd_help(ctx)
    if not text:
        raise StageFailed(f"{ctx.pd} not found — build it first")
    subs = re.findall(r"^\s{2}(\w[\w-]*)\s{2,}", text.split("Subcommands:")[-1], re.M)
    if name not in subs:
        raise StageFailed(f"this pd has no '{name}' subcommand yet ({ctx.rel(ctx.pd)} --help lists: "
                          f"{', '.join(subs) or 'nothing'}); the stage needs `pd {name}`")


def require_option(ctx: Ctx, sub: str, option: str) -> str:
    text = pd_help(ctx, sub)
    if option not in text:
        raise StageFailed(f"`pd {sub}` has no {option} option yet ({ctx.rel(ctx.pd)} {sub} --help); "
                          f"this stage needs `pd {sub} {option}`")
    return text


def parse_json_output(text: str) -> object:
    """A JSON document, or JSON lines (returned as a list)."""
    text = text.strip()
    if not text:
        raise ValueError("empty output")
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        pass
    rows = []
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("{") or line.startswith("["):
            obj = json.loads(line)
            rows.extend(obj if isinstance(obj, list) else [obj])
    if not rows:
        raise ValueError("no JSON in output")
    return rows


def read_jsonl(path: Path) -> list[dict]:
    rows = []
    for line in path.read_text().splitlines():
        line = line.strip()
        if line:
            rows.append(json.loads(line))
    return rows


def read_line_csv(path: Path) -> dict:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in (rows[0].keys() if rows else [])}


def scene_inputs(ctx: Ctx) -> list[Path]:
    v = ctx.root / "verification"
    files = sorted((v / "scenes").glob("*.yaml")) + sorted((v / "cases").glob("*/*.yaml"))
    files += sorted((ctx.root / "fem_reference" / "reference").glob("*"))
    return files


def drop_bulky(path: Path) -> None:
    """Delete VTU/PVD files of the runs so the report folder stays small enough to mail."""
    if path.is_dir():
        for p in list(path.rglob("*.vtu")) + list(path.rglob("*.pvd")):
            p.unlink(missing_ok=True)


# ---- FE references -----------------------------------------------------------------------------

def fe_problems(cases: dict[str, Case], order: list[str]) -> dict[str, list[Case]]:
    """The deal.II reference problems the structure cases compare with (their `fe_reference`),
    each with the cases that use it."""
    out: dict[str, list[Case]] = {}
    for name in order:
        out.setdefault(cases[name].fe_reference, []).append(cases[name])
    return out


def fem_stage(ctx: Ctx, problem: str, cases: list[Case]) -> Stage:
    prm = ctx.root / "fem_reference" / "prm" / f"{problem}.prm"
    gold = ctx.root / "fem_reference" / "reference" / f"{problem}.json"
    work = ctx.work / "fem" / problem
    fe_lines = [line for c in cases for line in c.lines]
    exe = ctx.bin / "pd-fem"
    cmd = [str(exe), str(prm), "-o", str(work), "--check", str(gold)]
    if not ctx.full:
        cmd.insert(2, "--coarse")

    def fn(ctx: Ctx, st: Stage) -> dict:
        if work.exists():
            shutil.rmtree(work)
        p = run(ctx, cmd, f"fem-{problem}", ok=(0, 2), env=st.env)
        check_passed = p.returncode == 0
        summary_run = json.loads((work / "summary.json").read_text())
        gold_summary = json.loads(gold.read_text())
        lines = {}
        if ctx.full:
            for line in fe_lines:
                if line.fe_run_csv and (work / line.fe_run_csv).exists():
                    lines[line.fe_csv] = read_line_csv(work / line.fe_run_csv)
            used = summary_run
        else:
            for line in fe_lines:
                lines[line.fe_csv] = read_line_csv(gold.parent / line.fe_csv)
            used = gold_summary
        tail = [l for l in (p.stdout + p.stderr).splitlines() if "CHECK" in l or "check" in l]
        result = {
            "problem": problem,
            "mode": "fresh full run" if ctx.full else "gold file + coarse check run",
            "check_passed": check_passed,
            "check_output": tail[-12:],
            "quantities": used["quantities"],
            "theory": used.get("theory", {}),
            "provenance": used.get("provenance", {}),
            "run_total_seconds": summary_run.get("wall_time_s"),
            "run_levels": [{k: lv.get(k) for k in ("level", "dofs", "deflection", "level_time_s")}
                           for lv in summary_run.get("levels", [])],
            "lines": lines,
        }
        drop_bulky(work)
        if not check_passed:
            raise StageFailed(
                f"pd-fem --check against {ctx.rel(gold)} FAILED: the FE program no longer "
                "reproduces its gold file:\n" + "\n".join(tail[-12:]), )
        return result

    return Stage(f"fem:{problem}", "fem", f"deal.II reference {problem}", [cmd],
                 [exe, prm, gold] + [gold.parent / line.fe_csv for line in fe_lines] + [c.path for c in cases], fn,
                 default_seconds=(90 if problem.startswith("plate") else 15) if ctx.full
                 else (15 if problem.startswith("plate") else 5),
                 # The coarse checks are small: one thread each, two side by side. The full runs
                 # keep the machine (deal.II's assembly uses every core).
                 env={} if ctx.full else {"DEAL_II_NUM_THREADS": "1"}, parallel=not ctx.full)


# ---- verification cases ------------------------------------------------------------------------

# Each run's entry in its case folder's case.yaml, as `pd verify --list --json` gives it (name,
# summary, folder, kind, label, cpu_seconds, threads, timeout, reference_kind, gate), by name.
CASE_METADATA: dict[str, dict] = {}


def list_cases(ctx: Ctx) -> list[tuple[str, str]]:
    p = run(ctx, [str(ctx.pd), "verify", "--list", "--json"], "verify-list")
    try:
        rows = json.loads(p.stdout)
    except json.JSONDecodeError as e:
        raise StageFailed(f"`pd verify --list --json` printed no JSON: {e}")
    if not rows:
        raise StageFailed("`pd verify --list --json` listed no cases")
    CASE_METADATA.clear()
    CASE_METADATA.update((r["name"], r) for r in rows)
    return [(r["name"], r["summary"]) for r in rows]


def verify_stage(ctx: Ctx, case: str, summary: str) -> Stage:
    work = ctx.work / "verify" / case
    cmd = [str(ctx.pd), "verify", case, "-o", str(work)] + ([] if ctx.full else ["--quick"])

    def fn(ctx: Ctx, st: Stage) -> dict:
        target = work / f"{case}.json"
        if work.exists():
            shutil.rmtree(work)
        p = run(ctx, cmd, f"verify-{case}", ok=(0, 2), env=st.env)   # 2 = a gate failed: still data
        if not target.exists():
            raise StageFailed(f"`{shlex.join(cmd)}` wrote no {target.name}")
        data = json.loads(target.read_text())
        data.setdefault("summary", summary)
        data["exit_code"] = p.returncode
        data["stdout_tail"] = p.stdout.splitlines()[-8:]
        drop_bulky(work)
        return data

    return Stage(f"verify:{case}", "verify", f"pd verify {case}", [cmd],
                 [ctx.pd] + scene_inputs(ctx), fn,
                 default_seconds=CASE_METADATA.get(case, {}).get("cpu_seconds", 60),
                 parallel=True)


# ---- scenes a new user writes, against deal.II ---------------------------------------------------

def user_scenes(ctx: Ctx) -> list[Path]:
    """verification/scenes/user/*.yaml that pd-fem can solve (elastic: no damage effect)."""
    out = []
    for p in sorted((ctx.root / "verification" / "scenes" / "user").glob("*.yaml")):
        if not re.search(r"^effects:.*damage", p.read_text(), re.M):
            out.append(p)
    return out


def scene_stage(ctx: Ctx, scene: Path) -> Stage:
    """`pd verify SCENE.yaml --fe-coarse`: the scene's PD run beside pd-fem --scene."""
    name = scene.stem
    work = ctx.work / "scene" / name
    cmd = [str(ctx.pd), "verify", str(scene), "--fe-coarse", "-o", str(work)]

    def fn(ctx: Ctx, st: Stage) -> dict:
        target = work / f"{name}.json"
        if work.exists():
            shutil.rmtree(work)
        run(ctx, cmd, f"scene-{name}", env=st.env)
        if not target.exists():
            raise StageFailed(f"`{shlex.join(cmd)}` wrote no {target.name}")
        data = json.loads(target.read_text())
        drop_bulky(work)
        return data

    return Stage(f"scene:{name}", "scene", f"pd verify {ctx.rel(scene)}", [cmd],
                 [ctx.pd, ctx.bin / "pd-fem", scene], fn, default_seconds=40,
                 env={"OMP_NUM_THREADS": "1", "DEAL_II_NUM_THREADS": "1"}, parallel=True)


# ---- sweeps ------------------------------------------------------------------------------------

def quick_sweep_tree(ctx: Ctx, case: str) -> Path:
    """A copy of verification/cases whose CASE folder's case.yaml keeps only the first value of each
    `sweep:` list (the default report's reduced sweep; --full runs the case file as it is)."""
    tree = ctx.work / "sweep-quick-tree"
    if tree.exists():
        shutil.rmtree(tree)
    shutil.copytree(ctx.root / "verification" / "cases", tree / "cases")
    f = tree / "cases" / case / "case.yaml"
    if f.exists():
        out, in_sweep = [], False
        for line in f.read_text().splitlines():
            if re.match(r"^sweep:", line):
                in_sweep = True
            elif in_sweep and re.match(r"^\S", line):
                in_sweep = False
            m = re.match(r"^(\s+\w+:\s*)\[([^\]]*)\](.*)$", line) if in_sweep else None
            if m:
                first = m.group(2).split(",")[0].strip()
                line = f"{m.group(1)}[{first}]   # reduced by the report (default mode)"
            out.append(line)
        f.write_text("\n".join(out) + "\n")
    return tree


def sweep_stage(ctx: Ctx, case: str, listed: set[str]) -> Stage:
    """`pd verify --sweep CASE` if pd offers it, else the `CASE-sweep` verification case."""
    work = ctx.work / "sweep" / case
    help_text = pd_help(ctx, "verify")
    quick = not ctx.full
    if "--sweep" in help_text:
        cmd = [str(ctx.pd), "verify", "--sweep", case, "-o", str(work)]
        if not ctx.full and "--quick" in help_text:
            cmd.append("--quick")  # the case file's quick_sweep lists
        quick = False  # pd decides the extent
    elif f"{case}-sweep" in listed:
        cmd = [str(ctx.pd), "verify", f"{case}-sweep", "-o", str(work)]
    else:
        cmd = [str(ctx.pd), "verify", "--sweep", case, "-o", str(work)]

    def fn(ctx: Ctx, st: Stage) -> dict:
        if "--sweep" not in help_text and f"{case}-sweep" not in listed:
            raise StageFailed(f"this pd offers neither `pd verify --sweep` ({ctx.rel(ctx.pd)} verify --help) "
                              f"nor a '{case}-sweep' case in `pd verify --list`; the sweep cannot run")
        if quick:
            quick_sweep_tree(ctx, case)
        if work.exists():
            shutil.rmtree(work)
        work.mkdir(parents=True)
        env = dict(st.env, PD_CASES_DIR=str(ctx.work / "sweep-quick-tree" / "cases")) if quick else st.env
        p = run(ctx, cmd, f"sweep-{case}", ok=(0, 2), env=env)
        rows: list[dict] = []
        for f in sorted(work.rglob("*.jsonl")):
            rows += read_jsonl(f)
        if not rows:
            for f in sorted(work.rglob("*sweep*.json")):
                obj = json.loads(f.read_text())
                rows += obj if isinstance(obj, list) else obj.get("rows", [])
        if not rows:
            try:
                obj = parse_json_output(p.stdout)
                rows = obj if isinstance(obj, list) else obj.get("rows", [])  # type: ignore[union-attr]
            except ValueError:
                pass
        rows = [r for r in rows if isinstance(r, dict) and "wall_seconds" in r]
        if not rows:
            raise StageFailed(f"`{shlex.join(cmd)}` produced no sweep rows (no *.jsonl / "
                              f"*sweep*.json in {ctx.rel(work)}, no JSON on stdout)")
        extra = {}
        summary = work / f"{case}-sweep.json"
        if summary.exists():
            sj = json.loads(summary.read_text())
            extra = {k: sj[k] for k in ("observed_order_in_spacing",) if k in sj}
        drop_bulky(work)
        return {"case": case, "command": cmd, "reduced": quick, "rows": rows, **extra}

    # Sweeps of the static solver run on one core each, two sweeps side by side.
    return Stage(f"sweep:{case}", "sweep", f"accuracy-vs-time sweep of {case}", [cmd],
                 [ctx.pd] + scene_inputs(ctx), fn, default_seconds=1800 if ctx.full else 60,
                 parallel=True)


# ---- stability ---------------------------------------------------------------------------------

def stability_stage(ctx: Ctx, scenes: list[str], integrators: list[str]) -> Stage:
    """`integrators` empty: every integrator `pd stability` offers."""
    paths = [ctx.root / "verification" / "cases" / s for s in scenes]
    cmd = [str(ctx.pd), "stability", *map(str, paths), "--json"]
    for name in integrators:
        cmd += ["--integrator", name]

    def fn(ctx: Ctx, st: Stage) -> dict:
        require_subcommand(ctx, "stability")
        p = run(ctx, cmd, "stability", env=st.env)
        try:
            obj = parse_json_output(p.stdout)
        except ValueError as e:
            raise StageFailed(f"`pd stability --json` printed no JSON ({e}):\n{p.stdout[-800:]}")
        rows = obj if isinstance(obj, list) else obj.get("rows", [])  # type: ignore[union-attr]
        if not rows:
            raise StageFailed("`pd stability --json` returned no rows")
        return {"rows": rows}

    # Stability and the two integrator comparisons run on one core each (a 1D bar, a coarse beam
    # below the threading threshold): two at a time.
    return Stage("stability", "stability", "stable time step per integrator", [cmd],
                 [ctx.pd] + paths, fn, default_seconds=240 if ctx.full else 60, parallel=not ctx.full)


# ---- integrator comparison ---------------------------------------------------------------------

def compare_stage(ctx: Ctx, which: str) -> Stage:
    out_file = ctx.work / "compare" / f"{which}.jsonl"
    cmd = [str(ctx.pd), "compare", which, "-o", str(out_file)]
    if not ctx.full:
        cmd.append("--quick")

    def fn(ctx: Ctx, st: Stage) -> dict:
        require_subcommand(ctx, "compare")
        out_file.parent.mkdir(parents=True, exist_ok=True)
        out_file.unlink(missing_ok=True)
        p = run(ctx, cmd, f"compare-{which}", env=st.env)
        rows = read_jsonl(out_file) if out_file.exists() else []
        if not rows:
            try:
                obj = parse_json_output(p.stdout)
                rows = obj if isinstance(obj, list) else [obj]  # type: ignore[list-item]
            except ValueError:
                pass
        if not rows:
            raise StageFailed(f"`{shlex.join(cmd)}` wrote no rows")
        return {"which": which, "rows": rows}

    return Stage(f"compare:{which}", "compare", f"integrator comparison ({which})", [cmd],
                 [ctx.pd] + scene_inputs(ctx), fn,
                 default_seconds=(90 if which == "dynamic" else 180) if ctx.full
                 else (30 if which == "dynamic" else 20), parallel=not ctx.full)


# ---- benchmarks --------------------------------------------------------------------------------

BENCH_SCENE = "verification/scenes/model-a-benchmark.yaml"


def bench_stage(ctx: Ctx) -> Stage:
    scene = ctx.root / BENCH_SCENE
    steps = "300"  # ~0.05 s per 2-thread repeat: shorter repeats scatter more than the effect
    repeats = "7" if ctx.full else "5"
    configs = [(s, 1) for s in ("exact", "modified", "fast")] + [(s, 2) for s in ("exact", "modified", "fast")]
    cmds = [[str(ctx.pd), "bench", str(scene), "--stretch", s, "--threads", str(t), "--steps", steps,
             "--repeats", repeats, "--json"] for s, t in configs]

    def fn(ctx: Ctx, st: Stage) -> dict:
        runs = []
        for (s, t), cmd in zip(configs, cmds):
            p = run(ctx, cmd, f"bench-{s}-{t}")
            j = parse_json_output(p.stdout)
            if not isinstance(j, dict):
                raise StageFailed(f"`{shlex.join(cmd)}` printed no JSON object")
            j["stretch"] = s
            j["threads_requested"] = t
            runs.append(j)
        return {"scene": BENCH_SCENE, "runs": runs, "loadavg": _loadavg()}

    return Stage("bench", "bench", "pd bench: bond updates per second", cmds, [ctx.pd, scene], fn,
                 default_seconds=40)


def kernel_stage(ctx: Ctx) -> Stage:
    exe = ctx.bin / "pd-kernel-bench"
    cmd = [str(exe), "--benchmark_format=json"]
    if ctx.full:
        cmd += ["--benchmark_repetitions=3", "--benchmark_report_aggregates_only=true"]
    else:
        cmd += ["--benchmark_min_time=0.2"]  # 33 benchmarks: 12 s instead of 30 at 0.5 s each

    def fn(ctx: Ctx, st: Stage) -> dict:
        p = run(ctx, cmd, "kernel-bench")
        try:
            j = json.loads(p.stdout)
        except json.JSONDecodeError as e:
            raise StageFailed(f"pd-kernel-bench printed no JSON: {e}")
        return {"context": j.get("context", {}), "benchmarks": j.get("benchmarks", [])}

    return Stage("kernel", "kernel", "pd-kernel-bench: cost of each effect", [cmd], [exe], fn,
                 default_seconds=60 if ctx.full else 25)


def lammps_stage(ctx: Ctx) -> Stage:
    script = ctx.root / "reports" / "lammps" / "run_lammps_bench.sh"
    inp = ctx.root / "reports" / "lammps" / "model-a.in"
    steps = "600" if ctx.full else "300"
    env = {"REPS": "3", "BENCH_DIAGNOSTIC": "1" if ctx.full else "0"}
    cmd = ["bash", str(script), steps]
    lmp = shutil.which(os.environ.get("LMP", "lmp"))

    def fn(ctx: Ctx, st: Stage) -> dict:
        if not script.exists():
            raise StageFailed(f"{ctx.rel(script)} does not exist yet (the LAMMPS peer script is "
                              "being written by another engineer)")
        p = run(ctx, cmd, "lammps", env=env)
        try:
            j = parse_json_output(p.stdout)
        except ValueError as e:
            raise StageFailed(f"run_lammps_bench.sh printed no JSON ({e}):\n{p.stdout[-600:]}")
        if not isinstance(j, dict):
            raise StageFailed("run_lammps_bench.sh printed JSON that is not an object")
        return j

    return Stage("lammps", "lammps", "LAMMPS peri/pmb on Model A", [cmd],
                 [script, inp] + ([Path(lmp)] if lmp else []), fn, default_seconds=40, env=env)


# libpd beside LAMMPS in one process that alternates them (pd bench --lammps): the ratio is taken
# per repeat under the same load, which is the figure issue 16's targets are stated in. LAMMPS's
# rate is read from its loop time (set-up excluded), about 6 s for 300 steps of Model A: the
# default report times 100 (2 s a repeat), --full 300.
PEER_CONFIGS = (("exact", False), ("exact", True), ("fast", False))


def peer_stage(ctx: Ctx) -> Stage:
    scene = ctx.root / BENCH_SCENE
    lmp = shutil.which(os.environ.get("LMP", "lmp"))
    inp = ctx.root / "reports" / "lammps" / "model-a.in"
    cmds = [[str(ctx.pd), "bench", str(scene), "--threads", "1", "--stretch", s, "--steps", "300",
             "--repeats", "7" if ctx.full else "3", "--lammps", lmp or "lmp",
             "--lammps-steps", "300" if ctx.full else "100", "--json"]
            + (["--damage"] if damage else []) for s, damage in PEER_CONFIGS]

    def fn(ctx: Ctx, st: Stage) -> dict:
        if not lmp:
            raise StageFailed("LAMMPS (lmp) is not installed: apt-get install lammps")
        runs = []
        for (s, damage), cmd in zip(PEER_CONFIGS, cmds):
            p = run(ctx, cmd, f"peer-{s}{'-damage' if damage else ''}")
            j = parse_json_output(p.stdout)
            if not isinstance(j, dict) or "ratio_to_lammps" not in j:
                raise StageFailed(f"`{shlex.join(cmd)}` printed no ratio")
            j["stretch"], j["damage"] = s, damage
            runs.append(j)
        return {"scene": BENCH_SCENE, "runs": runs}

    return Stage("peer", "lammps", "libpd and LAMMPS alternated (pd bench --lammps)", cmds,
                 [ctx.pd, scene, inp] + ([Path(lmp)] if lmp else []), fn, default_seconds=60)


# The virtual-fibre kernel beside the bond-based one on the same particles (pd bench --bond-model).
# Model A sets no correction, so both models hold the same bond family; block-tension takes the
# library's defaults, under which they do not (`gradient` weights drop the bond-based model's bonds
# beyond 2λ and its ghosts reach only those; the fibre model keeps the whole horizon).
FIBRE_BENCH_SCENES = ("verification/scenes/model-a-benchmark.yaml", "verification/cases/block-tension/block-tension.yaml")
BOND_MODELS = ("micro-elastic", "virtual-fibres")


def fibre_bench_stage(ctx: Ctx) -> Stage:
    rounds = 5 if ctx.full else 3
    configs = [(scene, model) for scene in FIBRE_BENCH_SCENES for model in BOND_MODELS]
    cmds = [[str(ctx.pd), "bench", str(ctx.root / scene), "--threads", "1", "--bond-model", model,
             "--steps", "20", "--repeats", "3", "--json"] for scene, model in configs]

    def fn(ctx: Ctx, st: Stage) -> dict:
        # Rounds alternate the two models, so both see the same load; the ratio is taken per round.
        rates: dict[tuple[str, str], list[dict]] = {c: [] for c in configs}
        loads = []
        for r in range(rounds):
            loads.append(_loadavg())
            for (scene, model), cmd in zip(configs, cmds):
                p = run(ctx, cmd, f"fibre-bench-{Path(scene).stem}-{model}-{r}", env=st.env)
                j = parse_json_output(p.stdout)
                if not isinstance(j, dict) or "bond_updates_per_second" not in j:
                    raise StageFailed(f"`{shlex.join(cmd)}` printed no rate")
                rates[(scene, model)].append(j)
        out = []
        for scene in FIBRE_BENCH_SCENES:
            runs = {m: rates[(scene, m)] for m in BOND_MODELS}
            ratios = [f["bond_updates_per_second"] / b["bond_updates_per_second"]
                      for b, f in zip(runs["micro-elastic"], runs["virtual-fibres"])]
            out.append({"scene": scene, "ratio_median": sorted(ratios)[len(ratios) // 2], "ratios": ratios,
                        "models": {m: {"particles": v[0]["particles"], "bonds": v[0]["bonds"],
                                       "kernel": v[0]["kernel"],
                                       "rates": [x["bond_updates_per_second"] for x in v],
                                       "median": sorted(x["bond_updates_per_second"] for x in v)[len(v) // 2],
                                       "under_load": any(x["under_load"] for x in v)}
                                   for m, v in runs.items()}})
        return {"rounds": rounds, "scenes": out, "loadavg": loads + [_loadavg()]}

    return Stage("fibre-bench", "bench", "virtual-fibre vs bond-based kernel (pd bench --bond-model)", cmds,
                 [ctx.pd] + [ctx.root / s for s in FIBRE_BENCH_SCENES], fn, default_seconds=60,
                 env={"OMP_NUM_THREADS": "1", "OMP_WAIT_POLICY": "passive"})


def mpi_stage(ctx: Ctx) -> Stage:
    """Strong scaling on Model C over 1, 2 and 4 MPI ranks (reports/mpi/scaling.py), and the
    bitwise-equality of their probes and energies."""
    script = ctx.root / "reports" / "mpi" / "scaling.py"
    scene = ctx.root / "reports" / "mpi" / "model-c-scaling.yaml"
    mpiexec = shutil.which("mpiexec")
    cmd = ["/usr/bin/python3", str(script), str(ctx.pd), "--rounds", "3" if ctx.full else "1",
           "--scene", str(scene), "--work", str(ctx.work / "mpi"), "--json"]

    def fn(ctx: Ctx, st: Stage) -> dict:
        if not mpiexec:
            raise StageFailed("mpiexec is not installed: apt-get install openmpi-bin")
        p = run(ctx, cmd, "mpi-scaling")
        j = parse_json_output(p.stdout)
        if not isinstance(j, dict) or "per_ranks" not in j:
            raise StageFailed("reports/mpi/scaling.py printed no scaling record")
        j["loadavg"] = _loadavg()
        return j

    return Stage("mpi", "mpi", "MPI strong scaling on Model C (1, 2, 4 ranks)", [cmd],
                 [ctx.pd, script, scene], fn, default_seconds=200 if ctx.full else 80)


def _loadavg() -> str:
    """The 1, 5 and 15 minute load averages, as "0.70 1.15 1.69"."""
    try:
        return " ".join(Path("/proc/loadavg").read_text().split(" ")[0:3])
    except OSError:
        return "?"


# ---- environment -------------------------------------------------------------------------------

def _cmd_out(cmd: list[str], cwd: Path | None = None) -> str:
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, timeout=30)
        return p.stdout.strip() if p.returncode == 0 else ""
    except (OSError, subprocess.TimeoutExpired):
        return ""


def environment(ctx: Ctx) -> dict:
    env: dict[str, object] = {}
    cm = (ctx.root / "CMakeLists.txt").read_text() if (ctx.root / "CMakeLists.txt").exists() else ""
    m = re.search(r"project\(\s*libpd\s+VERSION\s+([0-9.]+)", cm)
    env["libpd"] = m.group(1) if m else "unknown"
    for pkg, key in (("libdeal.ii-dev", "deal.II"), ("libsundials-dev", "SUNDIALS"),
                     ("lammps", "LAMMPS")):
        v = _cmd_out(["dpkg-query", "-W", "-f=${Version}", pkg])
        env[key] = v or "not installed"
    gxx = _cmd_out(["g++", "--version"])
    env["compiler"] = gxx.splitlines()[0] if gxx else "unknown"
    cache = ctx.build / "CMakeCache.txt"
    if cache.exists():
        m = re.search(r"^CMAKE_CXX_COMPILER:\w+=(.*)$", cache.read_text(), re.M)
        bt = re.search(r"^CMAKE_BUILD_TYPE:\w+=(.*)$", cache.read_text(), re.M)
        env["build_type"] = bt.group(1) if bt else "?"
        if m:
            env["cxx_used_by_build"] = m.group(1)
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    env["cpu"] = cpu
    env["cores"] = os.cpu_count()
    env["threads"] = int(os.environ.get("OMP_NUM_THREADS", os.cpu_count() or 1))
    env["date"] = time.strftime("%Y-%m-%d %H:%M:%S %Z")
    commit = _cmd_out(["git", "rev-parse", "HEAD"], cwd=ctx.root)
    if commit:
        dirty = _cmd_out(["git", "--no-optional-locks", "status", "--porcelain", "--untracked-files=no"], cwd=ctx.root)
        commit = commit[:12] + ("-dirty" if dirty else "")
    env["git_commit"] = commit or "unknown (not a git tree)"
    env["python"] = _cmd_out(["python3", "--version"]) or "?"
    try:
        import matplotlib
        env["matplotlib"] = matplotlib.__version__
    except ImportError:
        env["matplotlib"] = "missing"
    env["loadavg_at_start"] = _loadavg()
    env["build_dir"] = ctx.rel(ctx.build)
    return env
