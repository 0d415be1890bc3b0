"""The probes engineers read, under `pd verify SCENE.yaml`, in PD and in the FE reference, each
against a closed form (issue 37):

* a quarter plate in uniaxial tension (symmetry planes x = 0 and y = 0, a traction σ on the far
  edge as a force on its last particle layer, whose end effect the probes are three half-heights
  away from; plane stress): von Mises = σ_xx = σ, σ_xy = 0, ε_xx = σ/E, ε_yy = −ν σ/E, ε_xy = 0, in
  the bulk and at the free edge; a zero is judged against an absolute floor of σ (or σ/E);
* a 2D cantilever clamped by a held layer, with a transverse load on its end layer: the clamp's
  reaction moment about a point equals the load's moment about it, F times the load's arm, and its
  reaction force F (statics: both hold for any discretisation in equilibrium);
* a centre crack 2a in a plate pulled by grips: the opening at the centre (CMOD) against the FE
  and against 4 σ a / E (infinite plate) times the width factor of a periodic row of cracks
  (Koiter), σ from each solver's own grip reaction.
The tolerances are what each solver achieves at these spacings, printed; none is tuned per scene.
Needs pd-fem (PD_FEM, set by CMake)."""
import json
import math
import os

import pdcli

E, NU, T = 200e9, 1 / 3, 0.01


def steel_scene(title, spacing, rest):
    """A plane-stress steel scene (E, ν and thickness T above) at `spacing`, solved statically:
    the part the three scenes share, then `rest` (bodies, supports, loads, probes)."""
    return f"""\
title: "{title}"
dimension: 2
plane: stress
thickness: {T!r}
lattice:
  spacing: {spacing!r}
materials:
  steel:
    youngs_modulus: {E!r}
    poisson_ratio: {NU!r}
    density: 7800
solver:
  integrator: static
""" + rest


PLATE = steel_scene("Quarter plate in uniaxial tension (plane stress)", 0.0025, """\
bodies:
  - name: plate
    material: steel
    box: [[0, 0], [0.2, 0.05]]
supports:
  - name: plane-x
    symmetry: {x: 0}
  - name: plane-y
    symmetry: {y: 0}
loads:
  - name: pull
    box: [[0.1975, 0], [0.2, 0.05]]
    type: per_area
    value: [1e8, 0]
    measure: 0.0005
probes:
  - {name: vm_bulk, box: [[0.04, 0.02], [0.06, 0.03]], quantity: von_mises}
  - {name: vm_edge, point: [0.05, 0.04875], quantity: von_mises}
  - {name: sxx_bulk, point: [0.05, 0.02375], quantity: stress, component: xx}
  - {name: sxy_bulk, point: [0.05, 0.02375], quantity: stress, component: xy}
  - {name: sxy_edge, point: [0.05, 0.04875], quantity: stress, component: xy}
  - {name: syy_edge, point: [0.05, 0.04875], quantity: stress, component: yy}
  - {name: exx_bulk, point: [0.05, 0.02375], quantity: strain, component: xx}
  - {name: eyy_bulk, point: [0.05, 0.02375], quantity: strain, component: yy}
  - {name: eyy_edge, point: [0.05, 0.04875], quantity: strain, component: yy}
  - {name: exy_edge, point: [0.05, 0.04875], quantity: strain, component: xy}
""")
SIGMA = 1e8

CANTILEVER = steel_scene("2D cantilever, clamped layer, end load", 0.0025, """\
bodies:
  - name: beam
    material: steel
    box: [[0, 0], [0.4, 0.05]]
supports:
  - name: clamp
    box: [[0, 0], [0.0025, 0.05]]
    fixed: [x, y]
loads:
  - name: P
    box: [[0.3975, 0], [0.4, 0.05]]
    value: [0, -1000]
probes:
  - {name: moment, support: clamp, quantity: moment, about: [0, 0.025]}
  - {name: moment_far, support: clamp, quantity: moment, about: [0.2, 0.1]}
  - {name: shear_force, support: clamp, component: y}
""")
F, LOAD_X = 1000.0, 0.39875  # the load's particles (one layer) are at x = 0.4 − λ/2

CRACK = steel_scene("Centre crack in a plate pulled by grips (plane stress)", 0.002, """\
bodies:
  - name: plate
    material: steel
    box: [[0, 0], [0.2, 0.2]]
cracks:
  - name: centre
    segment: [[0.08, 0.1], [0.12, 0.1]]
supports:
  - name: bottom-grip
    box: [[0, 0], [0.2, 0.002]]
    displacement: {y: -1e-5}
    fixed: [x]
  - name: top-grip
    box: [[0, 0.198], [0.2, 0.2]]
    displacement: {y: 1e-5}
    fixed: [x]
probes:
  - {name: cmod, point: [0.1, 0.099], to: [0.1, 0.101], quantity: opening}
  - {name: grip_force, support: top-grip, component: y}
""")
A_CRACK, WIDTH = 0.02, 0.2


class VerifyProbes(pdcli.TestCase):
    def verify(self, text, name):
        scene = self.scene(name + ".yaml", text=text)
        out = self.path("verify-" + name)
        r = self.pd("verify", scene, "--fe-coarse", "-o", out, "--threads", "1", timeout=900)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        print(r.stdout, flush=True)
        with open(os.path.join(out, name + ".json"), encoding="utf-8") as f:
            d = json.load(f)
        return {p["name"]: (p["pd"], p["fe"]) for p in d["probes"]}

    def check(self, probes, name, exact, scale, pd_tol, fe_tol):
        """|value − exact| / scale within the tolerance, for PD and FE; printed either way."""
        v_pd, v_fe = probes[name]
        e_pd, e_fe = (v_pd - exact) / scale, (v_fe - exact) / scale
        print(f"{name}: exact {exact:.6g}, PD {v_pd:.6g} ({e_pd:+.3%} of {scale:.3g}), "
              f"FE {v_fe:.6g} ({e_fe:+.3%})", flush=True)
        self.assertLess(abs(e_pd), pd_tol, f"PD {name}")
        self.assertLess(abs(e_fe), fe_tol, f"FE {name}")

    def test_uniaxial_tension_stress_strain_von_mises(self):
        p = self.verify(PLATE, "plate-tension")
        eps = SIGMA / E
        # PD: 1 % in the bulk, 5 % at the free edge (the bond-based surface effect); FE 0.1 %.
        # A zero is judged against an absolute floor: σ for a stress, σ/E for a strain.
        for name, exact, scale, pd_tol in (
                ("vm_bulk", SIGMA, SIGMA, 1e-2), ("sxx_bulk", SIGMA, SIGMA, 1e-2),
                ("sxy_bulk", 0.0, SIGMA, 1e-2), ("exx_bulk", eps, eps, 1e-2),
                ("eyy_bulk", -NU * eps, eps, 1e-2), ("vm_edge", SIGMA, SIGMA, 5e-2),
                ("sxy_edge", 0.0, SIGMA, 5e-2), ("syy_edge", 0.0, SIGMA, 5e-2),
                ("eyy_edge", -NU * eps, eps, 5e-2), ("exy_edge", 0.0, eps, 5e-2)):
            self.check(p, name, exact, scale, pd_tol, 1e-3)

    def test_cantilever_reaction_moment_balances_the_load(self):
        p = self.verify(CANTILEVER, "cantilever-moment")
        # The support's moment balances the load's: about (0, 0.025) F x_load (the load points
        # −y); about (0.2, 0.1) F (x_load − 0.2). The FE is linear and exact to its solver's
        # tolerance; PD's static solve is geometrically nonlinear while the moment's arms are
        # the reference positions, which leaves a few 1e-6 of F x_load.
        self.check(p, "moment", F * LOAD_X, F * LOAD_X, 1e-5, 1e-6)
        self.check(p, "moment_far", F * (LOAD_X - 0.2), F * LOAD_X, 1e-5, 1e-6)
        self.check(p, "shear_force", F, F, 1e-6, 1e-6)

    def test_centre_crack_opening_against_fe_and_lefm(self):
        p = self.verify(CRACK, "crack-cmod")
        b = WIDTH / 2
        x = math.pi * A_CRACK / (2 * b)
        width_factor = 2 * b / (math.pi * A_CRACK) * math.acosh(1 / math.cos(x))
        cmod = {}
        for k, solver in enumerate(("PD", "FE")):
            sigma = p["grip_force"][k] / (WIDTH * T)
            infinite = 4 * sigma * A_CRACK / E
            cmod[solver] = p["cmod"][k]
            print(f"CMOD {solver}: {p['cmod'][k]:.6g} m; 4σa/E {infinite:.6g} m "
                  f"({p['cmod'][k] / infinite - 1:+.2%}); × width factor {width_factor:.5f}: "
                  f"{infinite * width_factor:.6g} m "
                  f"({p['cmod'][k] / (infinite * width_factor) - 1:+.2%})", flush=True)
            self.assertGreater(p["cmod"][k], 0)
            self.assertLess(abs(p["cmod"][k] / (infinite * width_factor) - 1), 0.1, solver)
        print(f"CMOD PD vs FE {cmod['PD'] / cmod['FE'] - 1:+.2%}", flush=True)
        self.assertLess(abs(cmod["PD"] / cmod["FE"] - 1), 0.1)


if __name__ == "__main__":
    pdcli.main()
