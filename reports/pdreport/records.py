"""What the stage records say: the readings that both the metrics (report.json) and the page are
built from, so the two cannot disagree about which runs, labels or points there are."""
from __future__ import annotations

import math


def ok(rec: dict | None) -> bool:
    return bool(rec) and rec.get("status") == "ok" and rec.get("result") is not None


def group(records: dict[str, dict], g: str) -> dict[str, dict]:
    return {k: v for k, v in records.items() if v.get("group") == g}


def flatten(d: object, prefix: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    if isinstance(d, dict):
        for k, v in d.items():
            out.update(flatten(v, f"{prefix}{k}."))
    elif isinstance(d, list):
        pass
    else:
        out[prefix.rstrip(".")] = d
    return out


def is_number(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def listed_cases(records: dict[str, dict], meta: dict) -> list[str]:
    """The cases of `pd verify --list` (stored in the meta), else those with a verify record."""
    return [c for c, _ in meta.get("cases", [])] or [n.split(":", 1)[1] for n in group(records, "verify")]


def run_size(d: dict) -> tuple[object, object]:
    """(particles, bonds) of a verification case's result."""
    run = d.get("run") or {}
    return d.get("particles", run.get("particles")), d.get("bonds", run.get("bonds"))


# ---- accuracy-vs-time sweeps ------------------------------------------------------------------

def sweep_error(r: dict) -> float | None:
    e = r.get("error_vs_fe")
    if isinstance(e, dict):
        vals = [abs(float(v)) for v in flatten(e).values() if is_number(v)]
        return max(vals) if vals else None
    if isinstance(e, (int, float)):
        return abs(float(e))
    return None


def corrections_of(r: dict) -> str:
    """A run's surface + volume correction pair, written as the case files' `corrections:` knob
    writes it ("ghost+gradient")."""
    return f"{r.get('surface_correction', '?')}+{r.get('volume_correction', '?')}"


def signed_sweep_errors(r: dict, fe: dict[str, float]) -> dict[str, float]:
    """(PD − FE)/FE per quantity of a sweep row: the row's own `signed_error_vs_fe`, else from its
    PD values and the FE values `fe` (rows written before the sign was recorded)."""
    own = r.get("signed_error_vs_fe")
    if isinstance(own, dict):
        return {q: float(v) for q, v in own.items() if is_number(v)}
    out = {}
    for q, v in (r.get("pd") or {}).items():
        if is_number(v) and is_number(fe.get(q)) and fe[q] != 0:
            out[q] = float(v) / fe[q] - 1.0
    return out


def sweep_points(rows: list[dict]) -> list[tuple]:
    """(wall seconds, error vs FE, knob, knob value, row) of each usable sweep row."""
    pts = []
    for r in rows:
        e = sweep_error(r)
        t = r.get("wall_seconds")
        if e is None or not t or t <= 0:
            continue
        pts.append((float(t), abs(e), str(r.get("knob", "?")), r.get("knob_value"), r))
    return pts


def pareto(pts: list[tuple]) -> list[tuple]:
    front = []
    best = math.inf
    for p in sorted(pts, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


# ---- integrators and benchmarks ---------------------------------------------------------------

def integrator_label(r: dict) -> str:
    return r.get("integrator", "?") + ("" if r.get("table") in (None, "-") else f":{r['table']}")


def quasistatic_label(r: dict) -> str:
    return integrator_label(r) + (" (adaptive)" if r.get("adaptive") else "")


STRETCHES = ("exact", "modified", "fast")


def bench_runs(result: dict) -> dict[tuple[str, int], dict]:
    """`pd bench` runs by (stretch, threads requested)."""
    return {(r["stretch"], r["threads_requested"]): r for r in result["runs"]}


def kernel_benchmarks(result: dict) -> list[dict]:
    """Google Benchmark rows: the iterations, or the medians when repetitions were aggregated."""
    return [b for b in result["benchmarks"]
            if b.get("run_type", "iteration") == "iteration" or b.get("aggregate_name") == "median"]


_UNIT_SCALE = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def kernel_seconds(b: dict) -> float:
    return float(b["real_time"]) * _UNIT_SCALE.get(b.get("time_unit", "ns"), 1e-9)


def kernel_name(b: dict) -> str:
    return b["name"].replace("/real_time", "")
