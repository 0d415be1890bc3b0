#!/usr/bin/env python3
"""`pd_report.py --compare` must flag regressions beyond noise and pass an unchanged report.

Builds a small synthetic report.json (metrics only) in a temporary folder, then:
  * unchanged copy                         -> exit 0
  * an error made 10 % worse               -> exit 1, names the metric
  * a bond-updates rate 10 % lower         -> exit 0 (timing noise band is 20 %)
  * a bond-updates rate 30 % lower         -> exit 1
  * a wall time 10 % longer / 30 % longer  -> 0 / 1
  * a value changed by 10 %                -> exit 1
  * a gate pass -> fail                    -> exit 1
  * a metric missing in the new report     -> exit 1
  * an error 0.5 % worse (below 1 %)       -> exit 0
  * an error 10 % better                   -> exit 0 (reported as improved)
Optionally also on a rendered report.json given as argv[1] (e.g. from the synthetic page).
"""
from __future__ import annotations

import copy
import json
import subprocess
import sys
import tempfile
from pathlib import Path

DRIVER = Path(__file__).resolve().parents[1] / "pd_report.py"

BASE = {
    "schema": "libpd-report/1",
    "metrics": {
        "verify.clamped-beam.error.midspan_vs_fe": {"value": 0.021, "kind": "error"},
        "verify.cantilever.error.tip_vs_fe": {"value": 0.0087, "kind": "error"},
        "verify.clamped-beam.pd.midspan": {"value": 1.43e-4, "kind": "value"},
        "verify.clamped-beam.passed": {"value": True, "kind": "gate"},
        "verify.clamped-beam.wall_seconds": {"value": 50.0, "kind": "time", "abs_tol": 1.0},
        "verify.clamped-beam.bonds": {"value": 231908, "kind": "count"},
        "bench.exact.t1.bond_updates_per_second": {"value": 5.0e7, "kind": "rate"},
    },
}


def run(old: dict, new: dict, tmp: Path, tag: str) -> tuple[int, str]:
    o, n = tmp / f"{tag}-old.json", tmp / f"{tag}-new.json"
    o.write_text(json.dumps(old))
    n.write_text(json.dumps(new))
    p = subprocess.run([sys.executable, str(DRIVER), "--compare", str(o), str(n)],
                       capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr


def scaled(base: dict, name: str, factor: float) -> dict:
    d = copy.deepcopy(base)
    d["metrics"][name]["value"] *= factor
    return d


def main() -> int:
    failures = []
    with tempfile.TemporaryDirectory(prefix="pd-report-compare-") as t:
        tmp = Path(t)
        cases = [
            ("unchanged", BASE, 0, None),
            ("error+10%", scaled(BASE, "verify.clamped-beam.error.midspan_vs_fe", 1.10), 1,
             "verify.clamped-beam.error.midspan_vs_fe"),
            ("rate-10%", scaled(BASE, "bench.exact.t1.bond_updates_per_second", 0.90), 0, None),
            ("rate-30%", scaled(BASE, "bench.exact.t1.bond_updates_per_second", 0.70), 1,
             "bench.exact.t1.bond_updates_per_second"),
            ("time+10%", scaled(BASE, "verify.clamped-beam.wall_seconds", 1.10), 0, None),
            ("time+30%", scaled(BASE, "verify.clamped-beam.wall_seconds", 1.30), 1,
             "verify.clamped-beam.wall_seconds"),
            ("value+10%", scaled(BASE, "verify.clamped-beam.pd.midspan", 1.10), 1,
             "verify.clamped-beam.pd.midspan"),
            ("error+0.5%", scaled(BASE, "verify.cantilever.error.tip_vs_fe", 1.005), 0, None),
            ("error-10%", scaled(BASE, "verify.cantilever.error.tip_vs_fe", 0.90), 0, None),
            ("bonds+1", scaled(BASE, "verify.clamped-beam.bonds", 1.0 + 1 / 231908), 1,
             "verify.clamped-beam.bonds"),
        ]
        gate = copy.deepcopy(BASE)
        gate["metrics"]["verify.clamped-beam.passed"]["value"] = False
        cases.append(("gate-fail", gate, 1, "verify.clamped-beam.passed"))
        missing = copy.deepcopy(BASE)
        del missing["metrics"]["verify.cantilever.error.tip_vs_fe"]
        cases.append(("missing", missing, 1, "verify.cantilever.error.tip_vs_fe"))
        if len(sys.argv) > 1:   # a rendered report.json: the same 10 % injection on a real layout
            real = json.loads(Path(sys.argv[1]).read_text())
            errs = [k for k, m in real["metrics"].items() if m["kind"] == "error" and m["value"]]
            cases.append(("rendered-unchanged", real, 0, None))
            cases.append(("rendered-error+10%", scaled(real, errs[0], 1.10), 1, errs[0]))
            rates = [k for k, m in real["metrics"].items() if m["kind"] == "rate"]
            if rates:
                cases.append(("rendered-rate-30%", scaled(real, rates[0], 0.7), 1, rates[0]))
        for tag, new, want, must_name in cases:
            old = BASE if not tag.startswith("rendered") else json.loads(Path(sys.argv[1]).read_text())
            rc, out = run(old, new, tmp, tag)
            ok = rc == want and (must_name is None or must_name in out)
            print(f"{'ok  ' if ok else 'FAIL'} {tag:<22} exit {rc} (want {want})")
            if not ok:
                failures.append(tag)
                print(out)
    if failures:
        print(f"FAILED: {', '.join(failures)}")
        return 1
    print("PASS: --compare flags every injected regression and passes unchanged/noise-level copies")
    return 0


if __name__ == "__main__":
    sys.exit(main())
