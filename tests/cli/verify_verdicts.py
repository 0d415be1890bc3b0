"""`pd verify SCENE.yaml` never gives a verdict it cannot stand behind (issue 37): both solvers
take one resolved material, a result without a tolerance is *measured*, an unconverged PD state
is not a verified one, and nonsense gates are refused. Needs pd-fem (PD_FEM, set by CMake)."""
import json
import os

import pdcli


def load(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)

STATIC = "  force_tolerance: 1e-10\n"


BAR = """title: balanced bar
dimension: 2
plane: stress
thickness: 0.01
lattice:
  spacing: 0.01
materials:
  steel:
    youngs_modulus: 200e9
    density: 7800
bodies:
  - name: bar
    material: steel
    box: [[0, 0], [0.4, 0.1]]
loads:
  - name: right
    box: [[0.39, 0], [0.4, 0.1]]
    type: total
    value: [1000, 0]
  - name: left
    box: [[0, 0], [0.01, 0.1]]
    type: total
    value: LEFT
solver:
  integrator: static
probes:
  - name: right_end
    box: [[0.39, 0], [0.4, 0.1]]
    component: x
  - name: top_lateral
    box: [[0.19, 0.09], [0.21, 0.1]]
    component: y
"""


class VerifyVerdicts(pdcli.TestCase):
    def verify(self, scene, *extra):
        out = self.path("verify")
        r = self.pd("verify", scene, "--fe-coarse", "-o", out, "--threads", "1", *extra)
        name = os.path.splitext(os.path.basename(scene))[0]
        path = os.path.join(out, name + ".json")
        return r, (load(path) if os.path.exists(path) else None)

    def static_scene(self, text_edit=lambda t: t):
        scene = self.scene(effects="", integrator="static", solver_extra="")
        with open(scene) as f:
            text = text_edit(f.read())
        with open(scene, "w") as f:
            f.write(text)
        return scene

    def test_without_a_gate_the_result_is_measured_and_both_solvers_use_nu_one_third(self):
        r, d = self.verify(self.static_scene())
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("MEASURED", r.stdout)
        self.assertEqual(d["verdict"], "measured")
        self.assertFalse(d["passed"])
        self.assertAlmostEqual(d["materials"][0]["poisson_ratio"], 1 / 3, places=15)
        fe = load(self.path("verify", "scene", "fe", "fe.json"))
        self.assertEqual(fe["materials"][0]["poisson_ratio"], d["materials"][0]["poisson_ratio"])

    def test_a_gate_judges_every_probe(self):
        r, d = self.verify(self.static_scene(), "--gate", "0.5")
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertEqual(d["verdict"], "passed")
        self.assertTrue(all(p["within_tolerance"] for p in d["probes"]))
        r, d = self.verify(self.static_scene(), "--gate", "1e-9")
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        self.assertEqual(d["verdict"], "failed")

    def test_an_unconverged_pd_run_is_not_verified(self):
        # Damped Euler stopped at end_time after a few steps: a transient, not an equilibrium.
        r, d = self.verify(self.scene(effects="damping", end_time="2e-6"), "--gate", "0.5")
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        self.assertEqual(d["verdict"], "failed")
        self.assertTrue(any("equilibrium" in why for why in d["reasons"]), d["reasons"])

    def test_a_poisson_ratio_bond_based_pd_cannot_represent_is_refused(self):
        scene = self.static_scene(lambda t: t.replace("density: 7850", "density: 7850\n    poisson_ratio: 0.25"))
        r, _ = self.verify(scene)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("different problems", r.stderr)

    def bar(self, left_value="[-1000, 0]"):
        """A plane-stress bar held by nothing, pulled by 1 kN at each end (poisson-control's shape)."""
        scene = self.path("bar.yaml")
        with open(scene, "w") as f:
            f.write(BAR.replace("LEFT", left_value))
        return scene

    def test_a_bar_held_only_by_balanced_loads_verifies(self):
        r, d = self.verify(self.bar(), "--gate", "0.05")
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertEqual(d["verdict"], "passed", d)
        probes = {p["name"]: p for p in d["probes"]}
        # Zero mean rigid motion on both sides: the end moves by F/(EA) times its distance from
        # the centroid, 5e-6 * 0.195 m, and the top row contracts by ν ε 0.045 m (ν = 1/3).
        self.assertAlmostEqual(probes["right_end"]["fe"] / (5e-6 * 0.195), 1, delta=0.01)
        self.assertAlmostEqual(probes["top_lateral"]["fe"] / (-5e-6 * 0.045 / 3), 1, delta=0.01)
        self.assertLess(abs(probes["right_end"]["relative_difference"]), 0.02)

    def test_a_free_body_under_unbalanced_loads_is_refused_with_what_to_add(self):
        r, _ = self.verify(self.bar("[-1000, 10]"))
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("not balanced", r.stderr)
        self.assertIn("add a support", r.stderr)

    def test_nonsense_gates_and_levels_are_refused(self):
        scene = self.static_scene()
        for extra in (["--gate", "nan"], ["--gate", "-1"], ["--gate", "0"], ["--gate", "2"],
                      ["--fe-levels", "-1"], ["--fe-levels", "9"]):
            r = self.pd("verify", scene, "-o", self.path("bad"), *extra)
            self.assertEqual(r.returncode, 1, f"{extra}: {r.stdout} {r.stderr}")
            self.assertFalse(os.path.exists(self.path("bad")), extra)


if __name__ == "__main__":
    pdcli.main()
