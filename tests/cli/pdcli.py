"""What the CLI tests share: the `pd` under test, a scratch folder per test and a tiny scene.

A test script does

    import pdcli
    class T(pdcli.TestCase):
        def test_x(self):
            r = self.pd("run", self.scene(), "-o", self.path("out"))
            self.assertEqual(r.returncode, 0, r.stderr)
    if __name__ == "__main__":
        pdcli.main()

and is run as `script.py --pd PATH/TO/pd` (tests/cli/CMakeLists.txt registers it).
"""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

PD = None

# A 1D-like bar of a few dozen particles: a run of it takes well under a second. Keys a test
# needs to change are filled in by TestCase.scene().
TINY_SCENE = """\
title: "tiny bar (CLI tests)"
dimension: 2
plane: stress
thickness: 0.01
lattice:
  spacing: 0.01
  horizon_factor: 3.015
materials:
  steel:
    youngs_modulus: 200e9
    density: 7850
bodies:
  - name: bar
    material: steel
    boxes:
      - [[0, 0, 0], [0.2, 0.03, 0]]
supports:
  - name: clamp
    box: [[0, 0, 0], [0.03, 0.03, 0]]
    fixed: [x, y]
loads:
  - name: pull
    box: [[0.17, 0, 0], [0.2, 0.03, 0]]
    value: [1e3, 0, 0]
effects: [{effects}]
solver:
  integrator: {integrator}
  dt: {dt}
  end_time: {end_time}
{solver_extra}probes:
  - name: tip_x
    box: [[0.19, 0, 0], [0.2, 0.03, 0]]
    component: x
output:
  vtu: {vtu}
  vtu_every: {vtu_every}
  history_every: 10
"""


class TestCase(unittest.TestCase):
    """A scratch folder per test (removed afterwards) and helpers to run pd in it."""

    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="pdcli-")
        self.addCleanup(shutil.rmtree, self.dir, ignore_errors=True)

    def path(self, *parts):
        return os.path.join(self.dir, *parts)

    def scene(self, name="scene.yaml", effects="damping", integrator="damped-euler",
              dt="auto", end_time="2e-4", solver_extra="  damping: 1e6\n", vtu="false",
              vtu_every=100, text=None):
        """Write the tiny scene (or `text`) into the scratch folder and return its path."""
        if text is None:
            text = TINY_SCENE.format(effects=effects, integrator=integrator, dt=dt,
                                     end_time=end_time, solver_extra=solver_extra, vtu=vtu,
                                     vtu_every=vtu_every)
        p = self.path(name)
        with open(p, "w", encoding="utf-8") as f:
            f.write(text)
        return p

    def pd(self, *args, timeout=120, **kwargs):
        """Run pd with `args`; returns the CompletedProcess (text output)."""
        return subprocess.run([PD, *map(str, args)], capture_output=True, text=True,
                              timeout=timeout, cwd=self.dir, **kwargs)


def main():
    global PD
    args = sys.argv[1:]
    if len(args) >= 2 and args[0] == "--pd":
        PD = os.path.abspath(args[1])
        args = args[2:]
    if PD is None or not os.access(PD, os.X_OK):
        sys.exit("usage: script.py --pd PATH/TO/pd [unittest args]")
    unittest.main(argv=[sys.argv[0], *args])
