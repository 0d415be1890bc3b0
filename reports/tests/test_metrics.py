#!/usr/bin/env python3
"""The metrics of report.json are computed from the stage records alone (pdreport/metrics.py), and
they are the ones the renderer used to record while it wrote the page.

    python3 reports/tests/test_metrics.py [WORKDIR]            # check
    python3 reports/tests/test_metrics.py WORKDIR --write      # rewrite the fixtures (a deliberate
                                                               # change of the metrics only)

Two record sets: the synthetic one (make_synthetic.py) and a variant of it that reaches the other
branches (pd verify --list in the meta with slow, failed, stale, cached, -fast and -sweep cases, a
failed sweep, unusable and non-finite values, kernel aggregates, a LAMMPS run).  For each:
  * metrics(records) equals tests/fixtures/metrics-NAME.json, names, order, kinds and values; the
    fixtures were written by the renderer of commit 3785b6a, which still recorded metrics as it
    rendered, so this pins the move; when the synthetic data grew (block-tension,
    clamped-beam-fast, the cantilever sweep, the old correction pairs, a fracture case) they were
    rewritten with --write and only gained metrics: every earlier one kept its value;
  * render() writes exactly those metrics into report.json.
"""
from __future__ import annotations

import copy
import json
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from pdreport import cases as case_files  # noqa: E402
from pdreport.metrics import metrics  # noqa: E402

FIXTURES = HERE / "fixtures"


def load(data: Path) -> tuple[dict[str, dict], dict, dict]:
    """The stage records in their stored order, the environment and the meta."""
    order = json.loads((data / "_order.json").read_text())
    recs = {r["name"]: r for r in (json.loads(f.read_text()) for f in data.glob("*.json")
                                   if not f.stem.startswith("_"))}
    return ({n: recs[n] for n in order}, json.loads((data / "_environment.json").read_text()),
            json.loads((data / "_meta.json").read_text()))


def variant(records: dict[str, dict], meta: dict) -> tuple[dict[str, dict], dict]:
    recs = copy.deepcopy(records)
    meta = copy.deepcopy(meta)
    listed = ["bond-count", "bar-vibration", "clamped-beam", "cantilever", "plate-3clamped",
              "clamped-beam-fast", "block-tension", "bar-energy", "clamped-beam-sweep", "cantilever-sweep"]
    meta["cases"] = [[c, f"synthetic {c}" + (" (slow)" if c == "block-tension" else "")] for c in listed]
    fast = copy.deepcopy(recs["verify:clamped-beam"])
    fast["name"], fast["cached"] = "verify:clamped-beam-fast", True
    fast["result"]["case"] = "clamped-beam-fast"
    fast["result"]["error"]["midspan_vs_fe"] = float("inf")
    recs[fast["name"]] = fast
    recs["verify:bar-energy"] = {"name": "verify:bar-energy", "group": "verify", "title": "x", "status": "failed",
                                 "error": "synthetic failure", "seconds": 3.0, "cached": False,
                                 "commands": [["synthetic"]], "result": None}
    stale = copy.deepcopy(recs["verify:bar-vibration"])
    stale["name"] = "verify:old-case"
    recs[stale["name"]] = stale
    recs["fem:cantilever"]["cached"] = True
    recs["sweep:clamped-beam"]["result"]["reduced"] = True
    sweep = recs["sweep:clamped-beam"]["result"]["rows"]
    sweep.append(dict(sweep[1], wall_seconds=0))
    sweep.append(dict(sweep[1], error_vs_fe={"a": {"b": 0.2}, "c": True}, knob_value="0.1"))
    sweep.append(dict(sweep[2], wall_seconds=151.0))
    recs["sweep:cantilever"] = {"name": "sweep:cantilever", "group": "sweep", "title": "x", "status": "failed",
                                "error": "synthetic", "seconds": 1.0, "cached": False, "commands": [], "result": None}
    stab = recs["stability"]["result"]["rows"]
    stab.append(dict(stab[0], integrator="euler-cromer", measured_dt=None, measured_over_sharp=float("nan")))
    dyn = recs["compare:dynamic"]["result"]["rows"]
    dyn.append(dict(dyn[0], table=None, dt_over_eq31=None))
    runs = recs["bench"]["result"]["runs"]
    runs[:] = [r for r in runs if not (r["stretch"] == "fast" and r["threads_requested"] == 2)]
    recs["kernel"]["result"]["benchmarks"] += [
        {"name": "Dispatched/elastic_exact_mean", "run_type": "aggregate", "aggregate_name": "mean",
         "real_time": 6.0, "time_unit": "ms"},
        {"name": "Dispatched/plastic_median/real_time", "run_type": "aggregate", "aggregate_name": "median",
         "real_time": 5000.0, "time_unit": "us"},
        {"name": "Plain/real_time", "real_time": 6.5e6}]
    pair = {"ns_per_bond_update_pair": 25.0, "median_pair_cpu_percent": 99.0}
    recs["lammps"] = {"name": "lammps", "group": "lammps", "title": "x", "status": "ok", "error": None,
                      "seconds": 20.0, "cached": False, "commands": [["bash", "run_lammps_bench.sh"]],
                      "result": {"threads": {"2": {"bond_updates_per_second": 7e7, **pair},
                                             "1": {"bond_updates_per_second": 4e7, **pair}},
                                 "atoms": 5229, "bonds_unordered": 319533, "lammps_version": "synthetic",
                                 "debian_package_version": "synthetic", "steps": 300, "repetitions": 3,
                                 "omp_note": "synthetic",
                                 "diagnostic_1_thread_bond_loop_only": {"bond_updates_per_second": 6e7, **pair}}}
    return recs, meta


def datasets(work: Path) -> list[tuple[str, dict[str, dict], dict, dict]]:
    subprocess.run([sys.executable, str(HERE / "make_synthetic.py"), str(work / "synthetic")], check=True,
                   capture_output=True)
    records, env, meta = load(work / "synthetic" / "data")
    v_records, v_meta = variant(records, meta)
    return [("synthetic", records, env, meta), ("variant", v_records, env, v_meta)]


def main(argv: list[str]) -> int:
    write = "--write" in argv
    args = [a for a in argv if a != "--write"]
    with tempfile.TemporaryDirectory(prefix="pd-report-metrics-") as t:
        work = Path(args[0]) if args else Path(t)
        failures = []
        for name, records, env, meta in datasets(work):
            got = metrics(records, meta, case_files.load())
            fixture = FIXTURES / f"metrics-{name}.json"
            if write:
                fixture.write_text(json.dumps(got, indent=1) + "\n")
            want = json.loads(fixture.read_text())
            same = json.dumps(got) == json.dumps(want)
            print(f"{'ok  ' if same else 'FAIL'} {name}: {len(got)} metrics computed from the records "
                  f"{'equal' if same else 'differ from'} {fixture.relative_to(HERE.parent)}")
            if not same:
                failures.append(name)
                for k in sorted(set(got) | set(want)):
                    if got.get(k) != want.get(k):
                        print(f"     {k}: computed {got.get(k)}, fixture {want.get(k)}")
                if list(got) != list(want) and set(got) == set(want):
                    print("     same metrics in another order")
            from pdreport.render import render  # matplotlib only from here on
            written = render(work / f"page-{name}", records, env, meta)["metrics"]
            same = json.dumps(written) == json.dumps(got)
            print(f"{'ok  ' if same else 'FAIL'} {name}: report.json holds exactly the computed metrics")
            if not same:
                failures.append(name + " (report.json)")
    if failures:
        print("FAILED: " + ", ".join(failures))
        return 1
    print("PASS: the metrics are a function of the stage records and match the fixtures")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
