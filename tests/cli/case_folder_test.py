#!/usr/bin/env python3
"""A verification case is one folder: a data-only case added by creating one folder appears in
`pd verify --list`, `pd verify --list --json`, ctest and the report's stages, with no other file
touched. In a temporary copy of verification/cases (PD_CASES_DIR):

  (a) `pd verify --list [--json]` list the new run with its summary and metadata;
  (b) the ctest include script (verification/runner/verification_tests.cmake), included by a
      one-line CTestTestfile.cmake, makes a test verify.NEW with its label, timeout and threads;
  (c) the report's stage list (reports/pd_report.py build_stages) has a stage verify:NEW.

    case_folder_test.py PD CMAKE_CTEST ROOT
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

NAME = "plate-hole-2d-vs-fe"
CASE_YAML = f"""summary: "a new user's data-only case: plate with a hole against deal.II"
kind: scene
references: ["deal.II FE (pd-fem --scene)"]
runs:
  - name: {NAME}
    summary: "plate with a hole (2D) vs deal.II, every probe within 5 %"
    label: verification-full
    cpu_seconds: 40
    threads: 1
    timeout: 1234
    reference_kind: "FE (deal.II)"
    gate: "every probe within 5 % of deal.II"
    scene: plate-hole-2d.yaml
    tolerance: 0.05
"""


def main() -> int:
    pd, ctest, root = Path(sys.argv[1]).resolve(), sys.argv[2], Path(sys.argv[3]).resolve()
    failures = []

    def check(ok: bool, what: str) -> None:
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failures.append(what)

    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        cases = tmp / "cases"
        shutil.copytree(root / "verification" / "cases", cases)
        folder = cases / NAME
        folder.mkdir()
        (folder / "case.yaml").write_text(CASE_YAML)
        shutil.copy(root / "verification" / "scenes" / "user" / "plate-hole-2d.yaml", folder)
        env = dict(os.environ, PD_CASES_DIR=str(cases))

        # (a)
        text = subprocess.run([str(pd), "verify", "--list"], env=env, capture_output=True,
                              text=True, check=True).stdout
        check(any(line.split(None, 1)[0] == NAME and "plate with a hole (2D)" in line
                  for line in text.splitlines() if line.strip()), "pd verify --list lists it")
        rows = json.loads(subprocess.run([str(pd), "verify", "--list", "--json"], env=env,
                                         capture_output=True, text=True, check=True).stdout)
        row = next((r for r in rows if r["name"] == NAME), None)
        check(row is not None and row["kind"] == "scene" and row["label"] == "verification-full"
              and row["timeout"] == 1234 and row["threads"] == 1
              and Path(row["folder"]) == folder, f"pd verify --list --json: {row}")
        source_env = {k: v for k, v in os.environ.items() if k != "PD_CASES_DIR"}
        plain = json.loads(subprocess.run([str(pd), "verify", "--list", "--json"], env=source_env,
                                          capture_output=True, text=True, check=True).stdout)
        check(NAME not in {r["name"] for r in plain}, "the source tree's list does not have it")

        # (b)
        project = tmp / "ctest"
        project.mkdir()
        (project / "CTestTestfile.cmake").write_text(
            f'set(PD_EXECUTABLE "{pd}")\nset(PD_VERIFY_OUT "{tmp / "out"}")\n'
            f'include("{root / "verification" / "runner" / "verification_tests.cmake"}")\n')
        shown = json.loads(subprocess.run([ctest, "--show-only=json-v1"], cwd=project, env=env,
                                          capture_output=True, text=True, check=True).stdout)
        tests = {t["name"]: {p["name"]: p["value"] for p in t.get("properties", [])}
                 for t in shown["tests"]}
        props = tests.get(f"verify.{NAME}", {})
        check(props.get("LABELS") == ["verification-full"] and float(props.get("TIMEOUT", 0)) == 1234
              and props.get("ENVIRONMENT") == ["OMP_NUM_THREADS=1"], f"ctest: verify.{NAME} {props}")
        check(len(tests) == len(rows) - sum(r["label"] == "none" for r in rows),
              f"ctest: one test per run with a label ({len(tests)} tests, {len(rows)} runs)")

        # (c)
        sys.path.insert(0, str(root / "reports"))
        os.environ["PD_CASES_DIR"] = str(cases)
        import pd_report   # re-runs this script under /usr/bin/python3 if matplotlib is missing
        from pdreport import stages as S
        ctx = S.Ctx(root=root, build=pd.parent.parent, out=tmp / "report")
        names = [st.name for st in pd_report.build_stages(ctx, {})]
        check(f"verify:{NAME}" in names, f"report stages have verify:{NAME}")
        stage = next(st for st in pd_report.build_stages(ctx, {}) if st.name == f"verify:{NAME}")
        check(stage.default_seconds == 40, f"its estimate is the case.yaml's cpu_seconds: {stage.default_seconds}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
