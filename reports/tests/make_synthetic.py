#!/usr/bin/env python3
"""Write a small SYNTHETIC set of stage records (DIR/data/*.json) for the report's own tests.

    python3 reports/tests/make_synthetic.py DIR

The numbers are made up (smooth functions with the right shapes and units) and the page says so in
its "mode" line; they exist only so the renderer, the browser check and --compare can be tested
without the heavy stages.  One stage (lammps) is a failed stage on purpose, so the failed-stage box
is exercised too.  The meta lists the cases as `pd verify --list` would (with one slow case the
default report skips and the sweeps); prints how many (= expected scorecard and summary rows).
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def rec(name: str, group: str, result: object, seconds: float = 1.0, status: str = "ok",
        error: str | None = None) -> dict:
    return {"name": name, "group": group, "title": name, "status": status, "error": error,
            "seconds": seconds, "cached": False, "commands": [["synthetic", name]], "result": result}


def beam_lines(case: str, n: int, scale: float) -> dict:
    rows = []
    for i in range(n):
        x = 3.5 * (i + 0.5) / n
        if case == "clamped-beam":
            fe = 1.4e-4 * 16 * (x / 3.5) ** 2 * (1 - x / 3.5) ** 2
        else:
            fe = 5.9e-3 * (x / 3.5) ** 2 * (6 - 4 * x / 3.5 + (x / 3.5) ** 2) / 3
        rows.append([x, fe * scale, fe])
    return {"centreline": {"columns": ["position", "pd", "fe"], "rows": rows,
                           "max_difference_over_max_fe": abs(scale - 1)}}


def structure(case: str, quantities: dict[str, tuple[float, float]], lines: dict, theory: dict,
              passed: bool) -> dict:
    pd, ref, err, gate = {}, {}, {}, {}
    for q, (fe, pdv) in quantities.items():
        pd[q] = pdv
        ref[q] = {"fe": fe, "fe_relative_error_estimate": 4e-4, **theory.get(q, {})}
        err[q + "_vs_fe"] = abs(pdv - fe) / fe
        for k, v in theory.get(q, {}).items():
            err[f"{q}_vs_{k}"] = abs(pdv - v) / v
    gate[next(iter(quantities)) + "_vs_fe"] = 0.03
    for name, l in lines.items():
        err[f"line_{name}_max_over_max_fe"] = l["max_difference_over_max_fe"]
    return {"case": case, "quantity": f"downward deflection at {', '.join(quantities)} (m)",
            "pd": pd, "reference": ref, "error": err, "gate": gate, "lines": lines,
            "passed": passed, "wall_seconds": 12.5, "particles": 4032, "bonds": 231908,
            "steps": 4600, "bond_updates": 1.07e9,
            "settings": {"spacing": 0.05, "horizon_factor": 3.464, "stretch": "exact"}}


def srow(case: str, knob: str, value: str, errors: dict[str, float], wall: float, **kw: object) -> dict:
    """One row of `pd verify CASE-sweep`: signed errors vs FE per quantity (FE taken as 1.4e-4)."""
    r = {"case": case, "knob": knob, "knob_value": value, "spacing": 0.05, "horizon_factor": 3.4641,
         "stretch": "exact", "surface_correction": "ghost", "volume_correction": "gradient",
         "force_tolerance": 1e-6, "status": "converged",
         "pd": {q: 1.4e-4 * (1 + e) for q, e in errors.items()},
         "error_vs_fe": {q: abs(e) for q, e in errors.items()}, "signed_error_vs_fe": dict(errors),
         "wall_seconds": wall, "steps": 4600, "bond_updates": 1e9, "particles": 4032, "bonds": 231908,
         "section_stiffness": {"bending": 0.98, "shear": 1.0}}
    r.update(kw)
    return r


def more_cases(verify: list[tuple[str, dict]]) -> list[tuple[str, dict]]:
    """A case gated in words with signed errors (block-tension) and a CI variant with its
    regression against the stored value (clamped-beam-fast)."""
    block = {"case": "block-tension", "quantity": "centre-line u_x at the loaded end and lateral strain",
             "pd": {"end_displacement": 1.0039e-3, "mid_displacement": 4.9e-4, "lateral_strain": -2.5215e-3},
             "reference": {"end_displacement": 1.0e-3, "mid_displacement": 4.875e-4, "lateral_strain": -2.5e-3},
             "error": {"elongation": 0.0039, "mid_displacement": 0.0051, "lateral_contraction": 0.0086},
             "signed_error": {"elongation": 0.0039, "lateral_contraction": 0.0086},
             "gate": "elongation error <= 0.5 %, lateral contraction error <= 2 %, steady state reached",
             "passed": True, "wall_seconds": 41.0, "particles": 8000, "bonds": 90000}
    fast = json.loads(json.dumps(dict(verify)["clamped-beam"]))
    fast.update(case="clamped-beam-fast", wall_seconds=5.3,
                regression={"midspan": {"stored": 1.43e-4, "relative_change": 2e-6, "tolerance": 1e-4}})
    return [("block-tension", block), ("clamped-beam-fast", fast)]


OLD_PAIRS = (("energy", "linear"), ("macek-silling", "linear"), ("tensor", "moment"))


def sweeps() -> list[dict]:
    """The clamped beam's complete sweep, the cantilever's spacing and old pairs only (the plate
    has none: the page says so)."""
    def cb(knob: str, value: str, err: float, wall: float, **kw: object) -> dict:
        return srow("clamped-beam", knob, value, {"midspan": err}, wall, **kw)
    rows = [cb("baseline", "scene", 0.02, 20.0)]
    for lam, e, w in ((0.1, 0.05, 3.0), (0.0333333, 0.009, 150.0)):
        rows.append(cb("spacing", f"{lam:.6g}", e, w, spacing=lam))
    for m, e, w in ((3.0, 0.025, 14.0), (4.0, 0.017, 31.0)):
        rows.append(cb("horizon_factor", f"{m:.6g}", e, w, horizon_factor=m))
    for st, e, w in (("modified", 0.0201, 19.0), ("fast", 0.0203, 17.0)):
        rows.append(cb("stretch", st, e, w, stretch=st))
    rows.append(cb("surface_correction", "none", 0.06, 19.5, surface_correction="none"))
    for t, e, w in ((1e-4, 0.03, 9.0), (1e-7, 0.02, 30.0)):
        rows.append(cb("force_tolerance", f"{t:.3g}", e, w, force_tolerance=t))
    # A finest level whose error stopped falling (it met the FE's own accuracy): outside the fit.
    rows.append(cb("spacing", "0.025", -0.0095, 400.0, spacing=0.025))
    for (sc, vc), e in zip(OLD_PAIRS, (0.026, -0.157, 0.134)):
        rows.append(cb("corrections", f"{sc}+{vc}", e, 18.0, surface_correction=sc, volume_correction=vc))
    cant = [srow("cantilever", "baseline", "scene", {"tip": 0.0011}, 4.0)]
    for lam, e, w in ((0.1, 0.004, 0.5), (0.0333333, 0.0004, 20.0)):
        cant.append(srow("cantilever", "spacing", f"{lam:.6g}", {"tip": e}, w, spacing=lam))
    for (sc, vc), e in zip(OLD_PAIRS, (-0.011, -0.12, 0.10)):
        cant.append(srow("cantilever", "corrections", f"{sc}+{vc}", {"tip": e}, 3.0,
                         surface_correction=sc, volume_correction=vc))
    return [rec("sweep:clamped-beam", "sweep", {"case": "clamped-beam", "rows": rows, "reduced": False,
                                                "observed_order_in_spacing": 1.5}, seconds=60),
            rec("sweep:cantilever", "sweep", {"case": "cantilever", "rows": cant, "reduced": False}, seconds=30)]


def tool_records() -> list[dict]:
    """Integrators, benchmarks and the LAMMPS stage (failed on purpose)."""
    out: list[dict] = []
    out.append(rec("stability", "stability", {"rows": [
        {"case": "bar-vibration", "integrator": integ, "interval": beta, "measured_dt": 3.3e-7 * beta / 2 * 1.05,
         "eq31_dt": 3.27e-7, "sharp_dt": 3.3e-7 * beta / 2, "measured_over_sharp": 1.05,
         "measured_over_eq31": 1.05 * beta / 2, "sharp_finite_horizon_dt": 3.4e-7 * beta / 2,
         "measured_over_sharp_finite_horizon": 1.01, "runs": 12, "wall_seconds": 0.4}
        for integ, beta in (("verlet", 2.0), ("arkode:rk4", 2.828), ("arkode:dormand-prince", 3.0))]}))
    dyn = []
    for integ, table, order in (("verlet", "-", 2), ("arkode", "rk4", 4)):
        for f in (0.9, 0.45, 0.225):
            ev = int(2000 / f * (4 if table == "rk4" else 1))
            dyn.append({"case": "bar-vibration", "integrator": integ, "table": table, "dt": 3e-7 * f,
                        "dt_over_eq31": f, "error": 0.012 + 0.05 * f**order, "error_vs_reference_pd": 0.05 * f**order,
                        "error_measure": "free-end history RMS / (eps L)", "force_evaluations": ev,
                        "wall_seconds": ev * 1e-4, "steps": int(2000 / f), "status": "completed"})
    out.append(rec("compare:dynamic", "compare", {"which": "dynamic", "rows": dyn}))
    qs = [{"case": "clamped-beam", "integrator": i, "table": t, "adaptive": a, "dt": dt, "midspan_deflection": w,
           "error": abs(w - 2.1778e-4) / 2.1778e-4, "force_tolerance": 1e-6, "residual": 6e-7,
           "force_evaluations": fe, "wall_seconds": fe * 4.6e-3, "steps": fe, "internal_steps": fe,
           "status": "converged"}
          for i, t, a, dt, w, fe in (("damped-euler", "-", False, 1.5e-4, 2.1778e-4, 4600),
                                     ("adr", "-", False, 1.0, 2.1779e-4, 900),
                                     ("arkode", "dormand-prince", True, 0, 2.1770e-4, 3100))]
    out.append(rec("compare:quasistatic", "compare", {"which": "quasistatic", "rows": qs}))
    runs = []
    for s, r1 in (("exact", 5.0e7), ("modified", 5.6e7), ("fast", 6.4e7)):
        for t in (1, 2):
            rate = r1 * (1.8 if t == 2 else 1)
            runs.append({"scene": "model-a", "kernel": f"stretch={s}", "threads": t, "threads_requested": t,
                         "stretch": s, "particles": 5229, "bonds": 319533, "steps": 100, "repeats": 5,
                         "seconds": 319533 * 100 / rate, "bond_updates_per_second": rate})
    out.append(rec("bench", "bench", {"scene": "verification/scenes/model-a-benchmark.yaml", "runs": runs,
                                      "loadavg": "['0.5', '0.5', '0.5']"}))
    benches = [{"name": f"{n}/real_time", "run_type": "iteration", "real_time": ms, "time_unit": "ms",
                "bond_updates_per_second": 319533 / (ms * 1e-3)}
               for n, ms in (("HandWrittenElastic", 6.0), ("Dispatched/elastic_exact", 6.1),
                             ("Dispatched/elastic_fast", 5.0), ("Dispatched/damage_exact", 7.2))]
    out.append(rec("kernel", "kernel", {"context": {"num_cpus": 2}, "benchmarks": benches}))
    out.append(rec("lammps", "lammps", None, status="failed", seconds=0.1,
                   error="synthetic: reports/lammps/run_lammps_bench.sh exited with code 127 "
                         "(LAMMPS binary 'lmp' not found) — the failed-stage box is part of the test"))
    return out


def fe_records() -> tuple[list[dict], dict[str, dict]]:
    """FE references: the real gold files (they are data in the repository, not a run); their
    stage records and the gold files by problem."""
    records = []
    ref = ROOT / "fem_reference" / "reference"
    golds = {}
    for p, csvs in (("clamped-beam", ["clamped-beam-centreline.csv"]),
                    ("cantilever", ["cantilever-centreline.csv"]),
                    ("plate-3clamped", ["plate-3clamped-perpendicular.csv", "plate-3clamped-free_edge.csv"])):
        g = json.loads((ref / f"{p}.json").read_text())
        golds[p] = g
        lines = {}
        for c in csvs:
            rows = [l.split(",") for l in (ref / c).read_text().splitlines()]
            head, body = rows[0], rows[1:]
            lines[c] = {h: [float(r[i]) for r in body] for i, h in enumerate(head)}
        records.append(rec(f"fem:{p}", "fem", {"problem": p, "mode": "synthetic", "check_passed": True,
                                                "quantities": g["quantities"], "theory": g["theory"],
                                                "lines": lines}))
    return records, golds


def plate_rows() -> tuple[list[list[float]], list[list[float]]]:
    """The plate's lines (position, PD, FE): perpendicular to the free edge and along it."""
    prow = []
    for i in range(60):
        y = 3.0 * (i + 0.5) / 60
        fe = 2.64e-4 * (y / 3) ** 2 * (3 - y / 3 * 1.4)
        prow.append([y, fe * 1.03, fe])
    erow = []
    for i in range(80):
        x = 4.0 * (i + 0.5) / 80
        fe = 2.64e-4 * 16 * (x / 4) ** 2 * (1 - x / 4) ** 2
        erow.append([x, fe * 1.03, fe])
    return prow, erow


def main(out: Path) -> int:
    data = out / "data"
    data.mkdir(parents=True, exist_ok=True)
    for f in data.glob("*.json"):
        f.unlink()
    records, golds = fe_records()
    t = {k: golds["clamped-beam"]["theory"][k] for k in ("euler_bernoulli", "timoshenko")}
    verify = [
        ("bond-count", {"case": "bond-count", "quantity": "particles and bonds", "passed": True,
                        "pd": {"model_a": {"particles": 5229, "bonds_inclusive": 319533}},
                        "reference": {"model_a": {"particles": 5229, "bonds": 313710}},
                        "error": {"model_a_bonds_vs_inclusive": 0.0186},
                        "gate": "strict <= paper <= inclusive", "wall_seconds": 1.0,
                        "bonds_per_particle_infinite_lattice": [
                            {"horizon_factor": m, "bonds_per_particle_strict": round(2 / 3 * math.pi * m**3) - 1,
                             "bonds_per_particle_inclusive": round(2 / 3 * math.pi * m**3),
                             "miranda_table1": round(2 / 3 * math.pi * m**3 - 0.5, 1),
                             "eq37": 2 / 3 * math.pi * m**3 - 0.5} for m in range(1, 9)]}),
        ("bar-vibration", {"case": "bar-vibration", "quantity": "free-end history", "passed": True,
                           "pd": {"period": 7.93e-4, "amplitude": 9.92e-4},
                           "reference": {"period": 7.92e-4, "amplitude": 9.97e-4},
                           "error": {"period": 8.7e-4, "amplitude": 5.6e-3},
                           "gate": {"period": 0.01, "amplitude": 0.02}, "wall_seconds": 2.5,
                           "run": {"particles": 1000, "bonds": 3000}}),
        ("clamped-beam", structure("clamped-beam", {"midspan": (1.395e-4, 1.43e-4)},
                                   beam_lines("clamped-beam", 70, 1.025), {"midspan": t}, True)),
        ("cantilever", structure("cantilever", {"tip": (5.911e-3, 5.99e-3)},
                                 beam_lines("cantilever", 70, 1.013),
                                 {"tip": {k: golds["cantilever"]["theory"][k] for k in ("euler_bernoulli", "timoshenko")}},
                                 False)),
        # A fracture case (the Fracture section lists it), shaped as kalthoff_winkler.cpp writes it.
        ("kalthoff-winkler", {"case": "kalthoff-winkler", "quantity": "crack angle", "passed": True,
                              "status": "end_time", "pd": {"angle_degrees": 70.4, "crack_points": 118},
                              "reference": {"angle_degrees": 70.0},
                              "error": {"angle_degrees": 0.0061}, "signed_error": {"angle_degrees": 0.0061},
                              "gate": "the crack leaves the notch tip within 5° of 70°",
                              "wall_seconds": 2.5}),
    ]
    prow, erow = plate_rows()
    kq = golds["plate-3clamped"]["theory"]["quantities"]
    verify.append(("plate-3clamped", structure(
        "plate-3clamped", {"free_edge_middle": (2.643e-4, 2.72e-4), "centre": (1.418e-4, 1.46e-4)},
        {"perpendicular": {"columns": ["position", "pd", "fe"], "rows": prow, "max_difference_over_max_fe": 0.03},
         "free_edge": {"columns": ["position", "pd", "fe"], "rows": erow, "max_difference_over_max_fe": 0.03}},
        {"free_edge_middle": {"kirchhoff": kq["free_edge_mid"]["kirchhoff"]},
         "centre": {"kirchhoff": kq["centre"]["kirchhoff"]}}, True)))
    verify += more_cases(verify)
    for case, d in verify:
        records.append(rec(f"verify:{case}", "verify", d, seconds=d["wall_seconds"]))
    records += sweeps()
    records += tool_records()
    for r in records:
        name = r["name"].replace(":", "_")
        (data / f"{name}.json").write_text(json.dumps(r))
    (data / "_order.json").write_text(json.dumps([r["name"] for r in records]))
    (data / "_environment.json").write_text(json.dumps({
        "libpd": "0.1.0", "git_commit": "synthetic", "deal.II": "synthetic", "SUNDIALS": "synthetic",
        "LAMMPS": "synthetic", "compiler": "synthetic", "cpu": "synthetic", "cores": 2, "threads": 2,
        "date": "synthetic", "build_dir": "-", "python": sys.version.split()[0], "matplotlib": "?"}))
    # As `pd verify --list` lists them: the cases run, one the default report leaves out as slow,
    # and the sweeps (two run, one not).
    listed = [[c, f"synthetic {c}"] for c, _ in verify]
    listed.insert([c for c, _ in listed].index("block-tension") + 1,
                  ["block-tension-corrections", "synthetic (slow)"])
    listed += [[f"{c}-sweep", "synthetic sweep"] for c in ("clamped-beam", "cantilever", "plate-3clamped")]
    (data / "_meta.json").write_text(json.dumps({
        "mode": "SYNTHETIC TEST DATA (reports/tests/make_synthetic.py) — not a real run",
        "total_seconds": sum(r["seconds"] for r in records), "cases": listed}))
    print(len(listed))
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: make_synthetic.py DIR")
    sys.exit(main(Path(sys.argv[1])))
