#!/usr/bin/env python3
"""tools/case_pages.py writes the verification-cases page from case folders.

Runs the generator on a fixture of two case folders made here, and checks what the page says and
what it refuses. If the tree has case folders and a committed docs/verification-cases.md, that
page must be what the generator writes from them.
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
import textwrap
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "case_pages.py"
sys.path.insert(0, str(ROOT / "tools"))
import case_pages  # noqa: E402

BAR = """\
summary: a bar's free vibration against its closed-form frequency
kind: code
references: [Miranda2019, closed-form]
runs:
  - name: bar-vibration
    summary: first mode, three periods
    label: verification
    cpu_seconds: 4
    threads: 1
    timeout: 300
    reference_kind: closed form
    gate: [frequency within 1 %, energy drift below 1e-6]
  - name: bar-vibration-sweep
    summary: accuracy against time step and spacing
    label: verification-full
    cpu_seconds: 120
    threads: 2
    timeout: 1800
    reference_kind: closed form
    gate: [observed order > 1]
"""
PLATE = """\
summary: "a plate with a hole | clamped on one edge"
kind: scene
references: []
runs:
  - name: plate-hole
    summary: tip deflection against deal.II
    label: verification
    cpu_seconds: 12
    threads: 1
    timeout: 600
    reference_kind: deal.II
    gate: [tip within 2 %]
"""


def make_cases(root: Path) -> Path:
    cases = root / "cases"
    (cases / "bar-vibration").mkdir(parents=True)
    (cases / "bar-vibration" / "case.yaml").write_text(BAR)
    (cases / "bar-vibration" / "README.md").write_text(textwrap.dedent("""\
        # Bar vibration

        ```sh
        pd verify bar-vibration
        ```

        The bar's first longitudinal mode,
        against its closed-form period.

        Further notes that the page does not quote.
        """))
    (cases / "plate-hole").mkdir()
    (cases / "plate-hole" / "case.yaml").write_text(PLATE)
    (cases / "not-a-case").mkdir()  # no case.yaml: not listed
    return cases


class CasePages(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.cases = make_cases(Path(self.tmp.name))

    def tearDown(self):
        self.tmp.cleanup()

    def generate(self, *args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True,
                              timeout=60)

    def test_page_lists_every_case_and_run(self):
        out = Path(self.tmp.name) / "page.md"
        run = self.generate(str(self.cases), str(out))
        self.assertEqual(run.returncode, 0, run.stderr)
        page = out.read_text()
        self.assertTrue(page.startswith("# Verification cases\n"))
        self.assertIn("| [bar-vibration](#bar-vibration) | code | a bar's free vibration "
                      "against its closed-form frequency | 1 / 1 |", page)
        self.assertIn("| [plate-hole](#plate-hole) | scene | a plate with a hole \\| clamped on "
                      "one edge | 1 / 0 |", page)
        self.assertNotIn("not-a-case", page)
        self.assertLess(page.index("## bar-vibration"), page.index("## plate-hole"))
        self.assertIn("| `bar-vibration` | first mode, three periods | default test run | 1 | 4 "
                      "| 300 | closed form | frequency within 1 %, energy drift below 1e-6 |", page)
        self.assertIn("| `bar-vibration-sweep` | accuracy against time step and spacing | report "
                      "only | 2 | 120 | 1800 | closed form | observed order > 1 |", page)
        self.assertIn("References: Miranda2019, closed-form.", page)
        # The README's first paragraph of prose, joined, is quoted; its title, code and later
        # paragraphs are not.
        self.assertIn("> The bar's first longitudinal mode, against its closed-form period.", page)
        self.assertNotIn("Further notes", page)
        self.assertIn("[README.md](../verification/cases/bar-vibration/README.md)", page)
        self.assertNotIn("plate-hole/README.md", page)

    def test_check_mode(self):
        out = Path(self.tmp.name) / "page.md"
        self.assertEqual(self.generate(str(self.cases), str(out)).returncode, 0)
        self.assertEqual(self.generate("--check", str(self.cases), str(out)).returncode, 0)
        (self.cases / "plate-hole" / "case.yaml").write_text(PLATE.replace("2 %", "3 %"))
        stale = self.generate("--check", str(self.cases), str(out))
        self.assertEqual(stale.returncode, 1)
        self.assertIn("out of date: run python3 tools/case_pages.py", stale.stderr)

    def test_bad_case_files_are_refused(self):
        for broken, message in (
                (PLATE.replace("kind: scene", "kind: movie"), "kind 'movie'"),
                (PLATE.replace("label: verification", "label: nightly"), "label 'nightly'"),
                (PLATE.replace("summary: \"a plate", "summry: \"a plate"), "missing 'summary'"),
                ("runs: [", "not valid YAML")):
            (self.cases / "plate-hole" / "case.yaml").write_text(broken)
            run = self.generate(str(self.cases))
            self.assertEqual(run.returncode, 1, broken)
            self.assertIn(message, run.stderr)
            self.assertIn("plate-hole/case.yaml", run.stderr)

    def test_committed_page_is_current(self):
        committed = ROOT / "docs" / "verification-cases.md"
        real = ROOT / "verification" / "cases"
        if not committed.is_file():
            self.skipTest("no docs/verification-cases.md in the tree")
        self.assertEqual(case_pages.main(["--check", str(real), str(committed)]), 0,
                         "docs/verification-cases.md is out of date: run python3 "
                         "tools/case_pages.py verification/cases docs/verification-cases.md")


if __name__ == "__main__":
    unittest.main()
