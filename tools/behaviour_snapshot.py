#!/usr/bin/env python3
"""Snapshot of everything libpd computes, to prove that a restructuring changed no number.

    python3 tools/behaviour_snapshot.py take BUILD_DIR OUT_DIR   # run the cases, store their output
    python3 tools/behaviour_snapshot.py diff OLD_DIR NEW_DIR     # exit 1 on any difference

`take` runs, with the `pd` of BUILD_DIR and one thread:
  * every verification case of the default test run (`pd verify`), its JSON;
  * `pd info --json` for every shipped scene;
  * `pd section --all-pairs --json` for the structural scenes;
  * the checkpoint test's runs (damped-euler, verlet and adr with bonds breaking, arkode rk4),
    whole and as half a run plus a restart: summary, probe history, VTU files and the checkpoint
    bytes themselves;
  * `pd stability --steps 200` on the bar.
Numbers are kept exactly (JSON floats round-trip), and only fields that measure the machine rather
than the model are dropped (wall times, rates, load, memory available, peak memory, the output
folder's lock, which holds the process id; durations inside messages; absolute paths keep only
their file name).
`diff` compares two snapshots file by file and byte by byte.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "reports"))
from pdreport.stages import parse_json_output  # noqa: E402

SCENES = ROOT / "verification" / "scenes"
CASE_FOLDERS = ROOT / "verification" / "cases"
CASES = ["bond-count", "bar-vibration", "bar-energy", "block-tension", "clamped-beam-fast",
         "cantilever-fast", "plate-3clamped-fast"]
SECTION_SCENES = [("clamped-beam/clamped-beam.yaml", []), ("cantilever/cantilever.yaml", []),
                  ("plate-3clamped/plate-3clamped.yaml", ["--plate"])]
# The checkpoint variants of tests/checkpoint/kill_restart_test.py (damped-euler, verlet and adr
# with bonds breaking, arkode rk4), each run whole and as half a run plus a restart.
CHECKPOINT_TEST = ROOT / "tests" / "checkpoint" / "kill_restart_test.py"
RUN_VARIANTS = ["damped-euler", "verlet", "adr", "arkode-rk4"]
MACHINE_WORDS = ("wall", "seconds", "per_second", "load_average", "memory_available",
                 "peak_memory", "pd-lock", "restarted_from", "checkpoint", "output_dir",
                 "scene_path", "threads")
# Durations inside free text (the static solver's summary message: "assembly 0.677 s, ...").
DURATION = re.compile(r"\b\d+\.\d+ s\b")


def machine_field(key: str) -> bool:
    return any(w in key for w in MACHINE_WORDS)


def normalise(value):
    if isinstance(value, dict):
        return {k: normalise(v) for k, v in value.items() if not machine_field(k)}
    if isinstance(value, list):
        return [normalise(v) for v in value]
    if isinstance(value, str) and value.startswith("/"):
        return Path(value).name  # where the tree or the snapshot lives is not a result
    if isinstance(value, str):
        return DURATION.sub("<duration>", value)
    return value


def write_json(path: Path, value) -> None:
    path.write_text(json.dumps(normalise(value), indent=1, sort_keys=True) + "\n")


def run(cmd: list[str], cwd: Path | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ, OMP_NUM_THREADS="1")
    return subprocess.run(cmd, cwd=cwd or ROOT, env=env, capture_output=True, text=True)


def json_lines(text: str):
    """Output of a `--json` command (the report's reader); [] when the command printed nothing."""
    return parse_json_output(text) if text.strip() else []


def checkpoint_scenes(variant: str, work: Path) -> tuple[Path, Path, int]:
    """The checkpoint test's scene for `variant`, and a copy that stops half-way (max_steps)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("kill_restart_test", CHECKPOINT_TEST)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    whole = work / f"{variant}.yaml"
    module.make_scene(str(CHECKPOINT_TEST.parent / "dogbone.yaml"), variant, str(whole))
    half_steps = module.VARIANTS[variant]["kill_at"]
    half = work / f"{variant}-half.yaml"
    half.write_text(whole.read_text().replace("solver:\n", f"solver:\n  max_steps: {half_steps}\n"))
    return whole, half, module.VARIANTS[variant]["checkpoint_every"]


def digest_tree(folder: Path) -> dict:
    out = {}
    for f in sorted(folder.rglob("*")):
        if not f.is_file():
            continue
        rel = str(f.relative_to(folder))
        if f.name == "summary.json":
            out[rel] = normalise(json.loads(f.read_text()))
        else:
            out[rel] = hashlib.sha256(f.read_bytes()).hexdigest()
    return out


def take(build: Path, out: Path) -> int:
    pd = str(build / "bin" / "pd")
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    work = out / "work"
    work.mkdir()
    failures = 0

    for case in CASES:
        r = run([pd, "verify", case, "-o", str(work / "verify")])
        f = work / "verify" / f"{case}.json"
        write_json(out / f"verify-{case}.json",
                   json.loads(f.read_text()) if f.exists() else {"exit": r.returncode})
        print(f"verify {case}: exit {r.returncode}", flush=True)

    # The shared scenes and the case folders' (not their case.yaml), by file name.
    shipped = list(SCENES.glob("*.yaml")) + [p for p in CASE_FOLDERS.glob("*/*.yaml")
                                              if p.name != "case.yaml"]
    for scene in sorted(shipped, key=lambda p: p.name):
        r = run([pd, "info", str(scene), "--json"])
        value = json.loads(r.stdout) if r.returncode == 0 else {"exit": r.returncode,
                                                               "stderr": r.stderr}
        write_json(out / f"info-{scene.stem}.json", value)

    for name, extra in SECTION_SCENES:
        r = run([pd, "section", str(CASE_FOLDERS / name), "--all-pairs", "--json", *extra])
        write_json(out / f"section-{Path(name).stem}.json",
                   {"exit": r.returncode, "rows": json_lines(r.stdout)})

    for variant in RUN_VARIANTS:
        whole, half, every = checkpoint_scenes(variant, work)
        full, restarted = work / f"{variant}-full", work / f"{variant}-restarted"
        every_arg = ["--checkpoint-every", str(every)]
        r1 = run([pd, "run", str(whole), "-o", str(full), *every_arg])
        r2 = run([pd, "run", str(half), "-o", str(restarted), *every_arg])
        r3 = run([pd, "run", str(whole), "-o", str(restarted), *every_arg, "--restart",
                  str(restarted / "checkpoint.pdcp")])
        write_json(out / f"run-{variant}.json", {
            "exit": [r1.returncode, r2.returncode, r3.returncode],
            "full": digest_tree(full),
            "restarted": digest_tree(restarted),
        })
        print(f"run {variant}: exit {r1.returncode} {r2.returncode} {r3.returncode}", flush=True)
        failures += r1.returncode != 0

    r = run([pd, "stability", str(CASE_FOLDERS / "bar-vibration" / "bar-vibration.yaml"), "--steps", "200", "--json",
             "--threads", "1"])
    write_json(out / "stability-bar.json", {"exit": r.returncode, "rows": json_lines(r.stdout)})
    shutil.rmtree(work)
    return 1 if failures else 0


def canonical(path: Path) -> str:
    return json.dumps(normalise(json.loads(path.read_text())), indent=1, sort_keys=True)


def diff(old: Path, new: Path) -> int:
    names = sorted({p.name for p in old.glob("*.json")} | {p.name for p in new.glob("*.json")})
    bad = 0
    for name in names:
        a, b = old / name, new / name
        if not a.exists() or not b.exists():
            print(f"only in one snapshot: {name}")
            bad += 1
        elif canonical(a) != canonical(b):
            print(f"differs: {name}")
            subprocess.run(["diff", str(a), str(b)], check=False)
            bad += 1
    print(f"{len(names) - bad} identical, {bad} different")
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] not in ("take", "diff"):
        print(__doc__)
        sys.exit(64)
    action = take if sys.argv[1] == "take" else diff
    sys.exit(action(Path(sys.argv[2]).resolve(), Path(sys.argv[3]).resolve()))
