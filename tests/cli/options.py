"""Command-line options that used to be accepted and then wrapped, hung or lied (issue 18, item 7).

Each test names the defect it guards; all of them failed before the fix.
"""
import re

import pdcli


class Options(pdcli.TestCase):
    def assertUsageError(self, *args, pattern=None):
        # A hang (tolerance 0) or a wrapped count runs into the timeout.
        r = self.pd(*args, timeout=60)
        self.assertEqual(r.returncode, 1, f"pd {' '.join(map(str, args))}: {r.stderr}")
        if pattern:
            self.assertRegex(r.stderr, pattern)
        return r

    def test_usage_errors_exit_1_not_cli11_codes(self):
        # CLI11's own codes were 104-114 (e.g. 106 "A subcommand is required").
        self.assertUsageError()
        self.assertUsageError("no-such-command")
        self.assertUsageError("run", "--no-such-option")
        self.assertUsageError("bench", self.scene(), "--steps", "abc")
        self.assertEqual(self.pd("--help").returncode, 0)
        self.assertEqual(self.pd("run", "--help").returncode, 0)

    def test_negative_counts_do_not_wrap(self):
        # `pd bench --steps -1` ran 2^64-1 evaluations; --checkpoint-every -1 became 1.8e19.
        scene = self.scene()
        self.assertUsageError("bench", scene, "--steps", "-1", pattern="--steps")
        self.assertUsageError("bench", scene, "--repeats", "-1", pattern="--repeats")
        self.assertUsageError("bench", scene, "--steps", "18446744073709551616")
        self.assertUsageError("run", scene, "--checkpoint-every", "-1",
                              pattern="--checkpoint-every")
        self.assertUsageError("stability", scene, "--steps", "-5")

    def test_threads_must_be_positive_and_are_capped(self):
        scene = self.scene()
        self.assertUsageError("bench", scene, "--threads", "0", pattern="--threads")
        self.assertUsageError("bench", scene, "--threads", "-3", pattern="--threads")
        # 10,000 threads ran 230x slower: capped to the processors, with a warning.
        r = self.pd("run", scene, "-o", self.path("out"), "--threads", "10000")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stderr, r"--threads 10000 is more than the \d+ processors")
        m = re.search(r"(\d+) threads", r.stdout)
        self.assertIsNotNone(m, r.stdout)
        self.assertLessEqual(int(m.group(1)), 1024)

    def test_stability_options_are_checked(self):
        # --tolerance 0 or negative hung; --steps 0 "measured" 2e6 x eq. 31; --gate nan turned
        # the gate off.
        scene = self.scene()
        for tol in ("0", "-0.1", "nan", "inf", "1"):
            self.assertUsageError("stability", scene, "--tolerance", tol, pattern="--tolerance")
        for steps in ("0", "1", "99"):
            self.assertUsageError("stability", scene, "--steps", steps, pattern="--steps")
        for gate in ("nan", "inf", "-1", "0"):
            self.assertUsageError("stability", scene, "--gate", gate, pattern="--gate")

    def test_stability_with_damage_measures_the_elastic_limit(self):
        # A scene with damage gave the same bogus limit as --steps 0: bonds broken by the growing
        # perturbation absorbed its energy. The limit is the elastic operator's, with or without
        # damage, and near eq. 31 (Verlet: at least eq. 31, at most a few times it).
        def measure(effects):
            text = pdcli.TINY_SCENE.format(
                effects=effects, integrator="verlet", dt="auto", end_time="1e-4",
                solver_extra="", vtu="false", vtu_every=100).replace(
                    "density: 7850\n", "density: 7850\n    critical_stretch: 1e-4\n")
            scene = self.scene(f"s-{effects.replace(', ', '-') or 'none'}.yaml", text=text)
            r = self.pd("stability", scene, "--integrator", "verlet", "--json", timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
            import json
            row = json.loads(r.stdout)[0]
            return row

        elastic = measure("")
        damaged = measure("damage")
        self.assertEqual(damaged["measured_dt"], elastic["measured_dt"])
        self.assertGreaterEqual(damaged["measured_dt"] / damaged["eq31_dt"], 1.0)
        self.assertLess(damaged["measured_dt"] / damaged["eq31_dt"], 4.0)


if __name__ == "__main__":
    pdcli.main()
