"""`pd verify SCENE.yaml` never gives a verdict it cannot stand behind (issue 37): both solvers
take one resolved material, a result without a tolerance is *measured*, an unconverged PD state
is not a verified one, and nonsense gates are refused. Needs pd-fem (PD_FEM, set by CMake)."""
import json
import math
import os
import subprocess

import junit_schema
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


PARTICLE_PLATE = """title: particle-file plate
dimension: 2
plane: stress
thickness: 0.01
lattice:
  spacing: 0.01
materials:
  steel:
    youngs_modulus: 200e9
    poisson_ratio: 0.3
    density: 7800
model:
  bond_model: virtual-fibres
bodies:
  - name: plate
    material: steel
    particles: plate.csv
supports:
  - name: clamp
    box: [[0, 0], [0.004, 0.04]]
    fixed: [x, y]
loads:
  - name: pull
    box: [[0.196, 0], [0.2, 0.04]]
    type: total
    value: [100, 0]
solver:
  integrator: adr
  end_time: 1
  max_steps: 200
probes:
  - name: end
    box: [[0.196, 0], [0.2, 0.04]]
    component: x
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
        # PD solves the FE's linear problem: bond forces linearised, no rotation stiffening.
        self.assertTrue(d["pd_small_displacements"])
        pd_summary = load(self.path("verify", "scene", "pd", "summary.json"))
        self.assertTrue(pd_summary["small_displacements"])
        self.assertIn("small displacements", r.stdout)
        # The summary line and summary.json count it as measured, not as passed.
        self.assertIn("0 passed, 1 measured (not judged), 0 failed", r.stdout)
        self.assertEqual(load(self.path("verify", "summary.json"))["status"], "measured")

    def tight_gate(self):
        """A gate every probe's difference exceeds and the FE can still judge (its own error
        estimate below half the tolerance), from a run with a loose gate."""
        _, d = self.verify(self.static_scene(), "--gate", "0.5")
        scales = [p["tolerance"] / 0.5 for p in d["probes"]]
        fe = max(p["fe_error_estimate"] / s for p, s in zip(d["probes"], scales))
        smallest = min(p["judged_difference"] for p in d["probes"])
        self.assertLess(2 * fe, smallest, "the FE cannot tell PD's differences from its own")
        return math.sqrt(2 * fe * smallest)

    def test_a_gate_judges_every_probe(self):
        r, d = self.verify(self.static_scene(), "--gate", "0.5")
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertEqual(d["verdict"], "passed")
        self.assertIn("1 passed, 0 failed", r.stdout)
        self.assertEqual(load(self.path("verify", "summary.json"))["status"], "passed")
        self.assertTrue(all(p["within_tolerance"] for p in d["probes"]))
        r, d = self.verify(self.static_scene(), "--gate", repr(self.tight_gate()))
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        self.assertEqual(d["verdict"], "failed")

    def test_a_gate_the_fe_cannot_judge_is_measured(self):
        """A tolerance below twice the FE's own error estimate gives no verdict: the reference
        cannot tell PD's error from its own."""
        r, d = self.verify(self.static_scene(), "--gate", "1e-9")
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertEqual(d["verdict"], "measured")
        self.assertIn("the FE's own error estimate", d["not_judged"])
        self.assertIn("0 passed, 1 measured (not judged), 0 failed", r.stdout)

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

    def test_junit_has_a_testcase_per_probe_and_validates(self):
        junit = self.path("verify.xml")
        r, d = self.verify(self.static_scene(), "--gate", repr(self.tight_gate()), "--junit", junit)
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        root = junit_schema.check(junit)
        suites = root.findall("testsuite")
        self.assertEqual([s.get("name") for s in suites], ["scene"])
        cases = {c.get("name"): c for c in suites[0].findall("testcase")}
        self.assertEqual(set(cases), {"verdict"} | {p["name"] for p in d["probes"]})
        self.assertIsNone(cases["verdict"].find("failure"))  # same materials, an equilibrium
        for p in d["probes"]:
            failure = cases[p["name"]].find("failure")
            self.assertIsNotNone(failure, p)  # no difference is within the tight gate
            out = cases[p["name"]].find("system-out").text
            self.assertIn(f"PD {p['pd']:.9g}", out)
            self.assertIn(f"FE {p['fe']:.9g}", out)
            self.assertIn("tolerance", out)
        self.assertGreater(float(cases["verdict"].get("time")), 0)
        self.assertEqual(int(root.get("failures")), len(d["probes"]))
        # Without a gate every probe is measured: skipped, nothing failed.
        r, d = self.verify(self.static_scene(), "--junit", junit)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        root = junit_schema.check(junit)
        self.assertEqual(int(root.get("failures")), 0)
        self.assertEqual(int(root.get("skipped")), len(d["probes"]) + 1)
        verdict = [c for c in root.iter("testcase") if c.get("name") == "verdict"][0]
        self.assertEqual(verdict.find("skipped").get("message"), "measured, not judged: no --gate")
        # A scene that cannot run is an error, recorded.
        r, _ = self.verify(self.bar("[-1000, 10]"), "--junit", junit)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        root = junit_schema.check(junit)
        self.assertEqual(int(root.get("errors")), 1)

    def test_case_mode_junit_validates(self):
        # A registered case (not a scene): one testsuite with one testcase, its gate.
        junit = self.path("cases.xml")
        out = self.path("cases")
        r = self.pd("verify", "bond-count", "-o", out, "--junit", junit)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("1 passed, 0 failed", r.stdout)
        root = junit_schema.check(junit)
        suites = root.findall("testsuite")
        self.assertEqual([s.get("name") for s in suites], ["bond-count"])
        cases = suites[0].findall("testcase")
        self.assertEqual(len(cases), 1)
        self.assertEqual([x.tag for x in cases[0] if x.tag != "system-out"], [])
        self.assertGreater(float(cases[0].get("time")), 0)
        self.assertEqual((root.get("tests"), root.get("failures"), root.get("errors"),
                          root.get("skipped")), ("1", "0", "0", "0"))
        self.assertEqual(load(os.path.join(out, "summary.json"))["cases"][0]["status"], "passed")

    def test_a_crack_through_particle_centres_is_refused_where_it_is(self):
        # The tiny bar's particle rows are at y = 0.005, 0.015, 0.025 (spacing 0.01).
        def crack(y):
            return lambda t: t.replace("probes:", f"cracks:\n  - name: c\n    segment: [[0.05, {y}], [0.15, {y}]]\nprobes:")
        r = self.pd("run", self.static_scene(crack(0.015)), "-o", self.path("row"))
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("crack 'c' runs through the centres of 10 particles (from [0.055, 0.015, 0] to [0.145, 0.015, 0])", r.stderr)
        self.assertIn("cell faces", r.stderr)
        self.assertNotIn("is the body held", r.stderr)
        r = self.pd("run", self.static_scene(crack(0.02)), "-o", self.path("face"))
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)

    def test_a_symmetry_plane_through_particle_centres_is_warned_about(self):
        def plane(x):
            return lambda t: t.replace("loads:", f"  - name: sym\n    symmetry: {{x: {x}}}\nloads:")
        r = self.pd("run", self.static_scene(plane(0.195)), "-o", self.path("centres"))
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("symmetry plane x = 0.195 of support 'sym' runs through the centres of 3 particles", r.stderr)
        r = self.pd("run", self.static_scene(plane(0.2)), "-o", self.path("face"))
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertNotIn("symmetry plane", r.stderr)

    def test_a_crack_of_no_length_is_a_scene_error_in_both_programs(self):
        scene = self.static_scene(lambda t: t.replace(
            "probes:", "cracks:\n  - name: dot\n    segment: [[0.1, 0.02], [0.1, 0.02]]\nprobes:"))
        r = self.pd("run", scene, "-o", self.path("run"))
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("crack 'dot' has no length", r.stderr)
        fe = subprocess.run([os.environ["PD_FEM"], "--scene", scene, "-o", self.path("fe"), "--coarse"],
                            capture_output=True, text=True, timeout=120)
        self.assertEqual(fe.returncode, 1, fe.stdout + fe.stderr)
        self.assertIn("crack 'dot' has no length", fe.stderr)
        self.assertNotIn("unknown exception", fe.stderr)

    def test_a_load_box_is_checked_against_a_particle_file_not_the_lattice(self):
        # 2 mm particles in a scene whose lattice spacing is 10 mm: the end boxes, 4 mm wide,
        # hold 40 particles each but no lattice point.
        with open(self.path("plate.csv"), "w") as f:
            f.write("x,y,volume\n")
            for i in range(100):
                for j in range(20):
                    f.write(f"{(i + 0.5) * 0.002},{(j + 0.5) * 0.002},{0.002 * 0.002 * 0.01}\n")
        scene = self.scene(text=PARTICLE_PLATE)
        r = self.pd("run", scene, "-o", self.path("run"), "--threads", "1")
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertNotIn("no particle", r.stderr)
        summary = load(self.path("run", "summary.json"))
        self.assertGreater(summary["probes"]["end"] if isinstance(summary["probes"], dict) else 1, 0)

    def test_fe_refinement_stops_before_the_memory_limit(self):
        scene = os.path.join(os.path.dirname(__file__), "..", "..", "verification", "scenes",
                             "user", "cantilever-point-load.yaml")
        env = dict(os.environ, PD_MEMORY_LIMIT="200M")
        fe = subprocess.run([os.environ["PD_FEM"], "--scene", scene, "-o", self.path("fe"),
                             "--levels", "6"], capture_output=True, text=True, timeout=300, env=env)
        self.assertEqual(fe.returncode, 0, fe.stdout + fe.stderr)
        self.assertIn("refinement stops at", fe.stderr)
        d = load(self.path("fe", "fe.json"))
        self.assertLess(len(d["levels"]), 6)
        self.assertGreaterEqual(len(d["levels"]), 1)
        self.assertIn("PD_MEMORY_LIMIT", d["refinement_stopped"])

    def test_nonsense_gates_and_levels_are_refused(self):
        scene = self.static_scene()
        for extra in (["--gate", "nan"], ["--gate", "-1"], ["--gate", "0"], ["--gate", "2"],
                      ["--fe-levels", "-1"], ["--fe-levels", "9"]):
            r = self.pd("verify", scene, "-o", self.path("bad"), *extra)
            self.assertEqual(r.returncode, 1, f"{extra}: {r.stdout} {r.stderr}")
            self.assertFalse(os.path.exists(self.path("bad")), extra)


if __name__ == "__main__":
    pdcli.main()
