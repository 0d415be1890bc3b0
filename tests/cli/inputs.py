"""Inputs without bounds (issue 18, items 3 and 9): files that never end, values that are huge,
bytes that are not text. Each test names the defect it guards; all of them failed before the fix.
"""
import json
import os

import pdcli


class Inputs(pdcli.TestCase):
    def assertFastError(self, *args, pattern=None):
        # A hang (the defect) runs into the timeout; no wall-time bound beyond that, since the
        # machines are shared.
        r = self.pd(*args, timeout=60)
        self.assertEqual(r.returncode, 1, f"pd {' '.join(map(str, args))}: {r.stderr}")
        self.assertLess(len(r.stderr), 2000, "the error echoes too much")
        if pattern:
            self.assertRegex(r.stderr, pattern)
        return r

    # /dev/zero or a FIFO as a scene or restart file was read forever.
    def test_scene_and_restart_must_be_regular_files(self):
        fifo = self.path("fifo")
        os.mkfifo(fifo)
        self.assertFastError("info", "/dev/zero", pattern="character device")
        self.assertFastError("info", fifo, pattern="FIFO")
        self.assertFastError("info", self.dir, pattern="directory")
        scene = self.scene()
        self.assertFastError("run", scene, "-o", self.path("a"), "--restart", "/dev/zero",
                             pattern="character device")
        self.assertFastError("run", scene, "-o", self.path("b"), "--restart", fifo, pattern="FIFO")

    def test_oversized_scene_and_huge_scalar(self):
        base = pdcli.TINY_SCENE.format(effects="damping", integrator="damped-euler", dt="auto",
                                       end_time="2e-4", solver_extra="  damping: 1e6\n",
                                       vtu="false", vtu_every=100)
        big = self.scene("big.yaml", text=base + "#" + "x" * (17 << 20) + "\n")
        self.assertFastError("info", big, pattern="more than the")
        huge = self.scene("huge.yaml", text=base.replace("youngs_modulus: 200e9",
                                                         "youngs_modulus: " + "9" * 10_000_000 + "x"))
        self.assertFastError("info", huge)

    # horizon_factor 1e9 hung; 1e19 gave NaN weights, "stable dt inf" and exit 0.
    def test_absurd_horizon_factor_is_refused_at_once(self):
        for m in ("1e9", "1e19"):
            text = self.scene_text().replace("horizon_factor: 3.015", f"horizon_factor: {m}")
            scene = self.scene(f"h{m}.yaml", text=text)
            for sub in ("info", "section", "run"):
                self.assertFastError(sub, scene, pattern="horizon_factor")

    # An invalid-UTF-8 title made summary.json unreadable; control bytes were printed raw.
    def test_summary_is_valid_utf8_json_and_output_is_escaped(self):
        text = self.scene_text().replace('"tiny bar (CLI tests)"', '"TITLE"').replace(
            "name: tip_x", 'name: "tip\\x1b[2Jx"')
        path = self.path("bad.yaml")
        with open(path, "wb") as f:
            f.write(text.encode().replace(b"TITLE", b"bad \xff\xfe title"))
        out = self.path("out")
        r = self.pd("run", path, "-o", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertNotIn("\x1b", r.stdout + r.stderr)
        with open(os.path.join(out, "summary.json"), "rb") as f:
            raw = f.read()
        summary = json.loads(raw.decode("utf-8"))  # strict: raises on invalid UTF-8
        self.assertIn("title", summary["title"])

    # Absurd settings ran without a word: E = 1e300 gave Δt = 4.5e-151 s; vtu_every 1 wrote
    # thousands of files.
    def test_absurd_run_sizes_are_warned_before_the_run(self):
        text = self.scene_text().replace("youngs_modulus: 200e9", "youngs_modulus: 1e300")
        text = text.replace("  damping: 1e6\n", "  damping: 1e6\n  max_steps: 100\n")
        r = self.pd("run", self.scene("e300.yaml", text=text), "-o", self.path("a"))
        # At Δt = 6e-151 s the displacements are below the positions' resolution: round-off
        # drives the run, and the energy watch may rightly call it unstable (exit 3).
        self.assertIn(r.returncode, (0, 3), r.stderr)
        self.assertRegex(r.stderr, r"warning: reaching end_time takes \S+e\+14\d steps")
        text = self.scene_text().replace("vtu: false", "vtu: true").replace(
            "vtu_every: 100", "vtu_every: 1").replace("end_time: 2e-4", "end_time: 2e-3")
        r = self.pd("run", self.scene("many.yaml", text=text), "-o", self.path("b"))
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stderr, r"warning: the run writes \d.\d+e\+03 VTU files")
        with open(os.path.join(self.path("b"), "summary.json"), encoding="utf-8") as f:
            self.assertTrue(any("VTU files" in w for w in json.load(f)["warnings"]))

    def scene_text(self):
        return pdcli.TINY_SCENE.format(effects="damping", integrator="damped-euler", dt="auto",
                                       end_time="2e-4", solver_extra="  damping: 1e6\n",
                                       vtu="false", vtu_every=100)


if __name__ == "__main__":
    pdcli.main()
