#!/usr/bin/env python3
"""The pages of docs/ that are generated, or copied, from one source are up to date with it.

    python3 tests/docs/generated_docs.py --pd build/bin/pd

* docs/scene-reference.md is what `pd run --print-scene-reference` prints from the schema;
* the README's first scene is docs/examples/cantilever-2d.yaml, character for character, and runs.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PD = "pd"
EXAMPLE = ROOT / "docs" / "examples" / "cantilever-2d.yaml"


class GeneratedDocs(unittest.TestCase):
    def test_scene_reference_is_current(self):
        out = subprocess.run([PD, "run", "--print-scene-reference"], capture_output=True,
                             text=True, timeout=60, check=True).stdout
        committed = (ROOT / "docs" / "scene-reference.md").read_text(encoding="utf-8")
        self.assertTrue(out == committed,
                        "docs/scene-reference.md differs from the scene schema: run "
                        "`build/bin/pd run --print-scene-reference > docs/scene-reference.md` "
                        "to update it")

    def test_reference_lists_every_section_and_key(self):
        # The writer walks the tables: spot-check that nested sections and shared ones appear.
        text = (ROOT / "docs" / "scene-reference.md").read_text(encoding="utf-8")
        for heading in ("## top level", "## `lattice`", "## `materials.NAME`", "## `bodies[]`",
                        "## `bodies[].minus[]`", "## `solver.steady`", "## `probes[]`"):
            self.assertIn(heading, text)
        for row in ("| `spacing` |", "| `youngs_modulus` |", "| `kinetic_tolerance` |",
                    "| `drops_below` |", "| `history_every` |"):
            self.assertIn(row, text)

    def test_readme_example_is_the_file_and_runs(self):
        readme = (ROOT / "README.md").read_text(encoding="utf-8")
        blocks = re.findall(r"```yaml\n(.*?)```", readme, flags=re.S)
        scene = EXAMPLE.read_text(encoding="utf-8")
        self.assertIn(scene, blocks, "the README's scene differs from docs/examples/"
                      "cantilever-2d.yaml: copy the file into the README")
        with tempfile.TemporaryDirectory() as tmp:
            run = subprocess.run([PD, "run", str(EXAMPLE), "-o", str(Path(tmp) / "out"),
                                  "--threads", "1"], capture_output=True, text=True, timeout=100)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertIn("status converged", run.stdout)
        # The README quotes the probe's printed value; it must be what the run prints. The static
        # solve is exact only to its residual (about 1e-8 of the load), and its last digits follow
        # the CPU's BLAS kernels, so the two agree to 1e-6, far below any change of the model.
        printed = re.search(r"probe tip_deflection +(\S+)", run.stdout)
        quoted = re.search(r"probe tip_deflection +(\S+)", readme)
        self.assertIsNotNone(printed, run.stdout)
        self.assertIsNotNone(quoted, "the README quotes no tip deflection")
        self.assertLessEqual(abs(float(quoted.group(1)) - float(printed.group(1))),
                             1e-6 * abs(float(printed.group(1))),
                             f"the README's tip deflection {quoted.group(1)} is not what the "
                             f"example prints ({printed.group(1)}): paste the run's output")


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--pd", default="pd")
    args, rest = parser.parse_known_args()
    PD = args.pd
    unittest.main(argv=[sys.argv[0]] + rest)
