"""`pd run` at the edges of what a scene can do (issue 38): each test names its item and failed
before the fix.
"""
import json
import os
import re

import pdcli

SCENES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "verification",
                      "scenes")


class RunLimits(pdcli.TestCase):
    # Item 8: a very stiff cantilever under Verlet stopped as "unstable" at step 20 with "work
    # of the loads 0 J": its particles moved less than their positions' round-off, so the work
    # fed into its kinetic energy was seen nowhere. Δt was within the limit.
    def test_motion_below_round_off_is_not_an_instability(self):
        with open(os.path.join(SCENES, "cantilever-2d.yaml"), encoding="utf-8") as f:
            text = f.read()
        text = text.replace("    density: 2400\n", "    density: 2400\n    stiffness_factor: 1e12\n")
        text = re.sub(r"\n  integrator: static\n", "\n  integrator: verlet\n  end_time: 1e-8\n",
                      text)
        out = self.path("out")
        r = self.pd("run", self.scene("stiff.yaml", text=text), "-o", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
            self.assertEqual(json.load(f)["status"], "end_time")


if __name__ == "__main__":
    pdcli.main()
