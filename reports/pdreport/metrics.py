"""The metrics of report.json that `pd_report.py --compare` diffs between two reports.

A pure function of the stage records (and the case list of the meta, and the case files): the page
is rendered from the same records but plays no part in what is measured.  Each metric is
{"value", "kind", ...}; the kind sets the noise band compare.py allows (see compare.py).  The order
of the metrics follows the page, section by section.
"""
from __future__ import annotations

import math

from . import records as R
from .cases import Case, in_listed_order
from .fmt import fnum, short


class _Metrics(dict):
    def add(self, name: str, value: object, kind: str, **extra: object) -> None:
        """Record a metric; a missing or non-finite value is no measurement and is left out."""
        if value is None:
            return
        if isinstance(value, float) and not math.isfinite(value):
            return
        self[name] = {"value": value, "kind": kind, **extra}


def metrics(records: dict[str, dict], meta: dict, cases: dict[str, Case]) -> dict[str, dict]:
    m = _Metrics()
    _verification(m, records, meta)
    _deflection_lines(m, records, meta, cases)
    _sweeps(m, records)
    _integrators(m, records)
    _performance(m, records)
    for name, rec in records.items():
        m.add(f"stage.{name}.ok", rec.get("status") == "ok", "gate")
        if rec.get("status") == "ok" and not rec.get("cached"):
            m.add(f"stage.{name}.seconds", rec.get("seconds"), "time", abs_tol=5.0)
    return dict(m)


def _verification(m: _Metrics, records: dict[str, dict], meta: dict) -> None:
    verify = R.group(records, "verify")
    for case in R.listed_cases(records, meta):
        rec = verify.get(f"verify:{case}")
        if rec is None:     # not run in this mode, or a sweep (measured in _sweeps)
            continue
        if not R.ok(rec):
            m.add(f"verify.{case}.passed", False, "gate")
            continue
        d = rec["result"]
        for k, v in R.flatten(d.get("error", {})).items():
            if R.is_number(v):
                m.add(f"verify.{case}.error.{k}", v, "error")
        for k, v in R.flatten(d.get("pd", {})).items():
            if R.is_number(v):
                m.add(f"verify.{case}.pd.{k}", v, "count" if isinstance(v, int) else "value")
        m.add(f"verify.{case}.passed", bool(d.get("passed")), "gate")
        m.add(f"verify.{case}.wall_seconds", d.get("wall_seconds"), "time", abs_tol=1.0)
        particles, bonds = R.run_size(d)
        m.add(f"verify.{case}.particles", particles, "count")
        m.add(f"verify.{case}.bonds", bonds, "count")


def _deflection_lines(m: _Metrics, records: dict[str, dict], meta: dict, cases: dict[str, Case]) -> None:
    for case in in_listed_order(cases, R.listed_cases(records, meta)):
        rec = records.get(f"verify:{case}")
        if R.ok(rec):
            for line, ldata in (rec["result"].get("lines") or {}).items():
                m.add(f"line.{case}.{line}.max_difference_over_max_fe",
                      ldata.get("max_difference_over_max_fe"), "error")


def _sweeps(m: _Metrics, records: dict[str, dict]) -> None:
    for name, rec in R.group(records, "sweep").items():
        if not R.ok(rec):
            continue
        case = name.split(":", 1)[1]
        for t, e, knob, value, _ in R.sweep_points(rec["result"]["rows"]):
            key = f"sweep.{case}.{knob}={short(value)}"
            m.add(key + ".error", e, "error")
            m.add(key + ".wall_seconds", t, "time", abs_tol=1.0)


def _rows(records: dict[str, dict], stage: str) -> list[dict]:
    rec = records.get(stage)
    return rec["result"]["rows"] if R.ok(rec) else []


def _integrators(m: _Metrics, records: dict[str, dict]) -> None:
    for r in _rows(records, "stability"):
        key = f"stability.{r.get('case')}.{r.get('integrator')}"
        m.add(key + ".measured_dt", r.get("measured_dt"), "value")
        m.add(key + ".measured_over_sharp", r.get("measured_over_sharp"), "value")
    for r in _rows(records, "compare:dynamic"):
        key = f"compare.dynamic.{R.integrator_label(r)}.dt{fnum(r.get('dt_over_eq31'), 3)}"
        m.add(key + ".error", r.get("error"), "error")
        m.add(key + ".force_evaluations", r.get("force_evaluations"), "count")
    for r in _rows(records, "compare:quasistatic"):
        key = f"compare.quasistatic.{R.quasistatic_label(r)}"
        m.add(key + ".wall_seconds", r.get("wall_seconds"), "time", abs_tol=0.5)
        m.add(key + ".error", r.get("error"), "error")


def _performance(m: _Metrics, records: dict[str, dict]) -> None:
    rec = records.get("bench")
    if R.ok(rec):
        by = R.bench_runs(rec["result"])
        for s in R.STRETCHES:
            for t in (1, 2):
                r = by.get((s, t))
                if r:
                    m.add(f"bench.{s}.t{t}.bond_updates_per_second", r.get("bond_updates_per_second"), "rate")
    rec = records.get("kernel")
    if R.ok(rec):
        for b in R.kernel_benchmarks(rec["result"]):
            name = R.kernel_name(b)
            m.add(f"kernel.{name}.seconds", R.kernel_seconds(b), "time", abs_tol=0.0)
            rate = b.get("bond_updates_per_second")
            if rate:
                m.add(f"kernel.{name}.bond_updates_per_second", rate, "rate")
    rec = records.get("peer")
    if R.ok(rec):
        for r in rec["result"]["runs"]:
            key = f"peer.{r['stretch']}{'.damage' if r['damage'] else ''}"
            m.add(key + ".ratio_to_lammps", r.get("ratio_to_lammps"), "rate")
    rec = records.get("threads-under-load")
    if R.ok(rec):
        for r in rec["result"]["scenes"]:
            key = "threads_under_load." + r["scene"].rsplit("/", 1)[-1].removesuffix(".yaml")
            # A ratio of two times on one machine: compared like a time, with 0.1 for its noise.
            m.add(key + ".ratio", r.get("ratio"), "time", abs_tol=0.1)
            if r.get("identical") is not None:
                m.add(key + ".bitwise_across_threads", r["identical"], "gate")
    rec = records.get("lammps")
    if R.ok(rec):
        for t, r in sorted(rec["result"].get("threads", {}).items()):
            m.add(f"lammps.t{t}.bond_updates_per_second", r.get("bond_updates_per_second"), "rate")
    rec = records.get("verify:bond-count")
    if R.ok(rec):
        for r in rec["result"].get("bonds_per_particle_infinite_lattice") or []:
            m.add(f"bond_count.m{r.get('horizon_factor')}.inclusive", r.get("bonds_per_particle_inclusive"), "count")
