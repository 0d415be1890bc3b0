"""Compare two report.json files and list what got worse beyond noise.

Every number the CI should watch is in report.json under "metrics" as
    "NAME": {"value": V, "kind": KIND[, "abs_tol": T]}
and the kind decides what "worse" and "noise" mean:

| kind  | better | regression when                                                            |
|-------|--------|----------------------------------------------------------------------------|
| error | lower  | new − old > max(1 % of |old|, abs_tol)          abs_tol default 1e-5       |
| value | —      | |new − old| > max(1 % of |old|, abs_tol)        abs_tol default 1e-12      |
|       |        | (a changed result is reported, whichever direction)                        |
| count | —      | new != old (particles, bonds: the model itself changed)                    |
| time  | lower  | new > 1.2 × old and new − old > abs_tol         abs_tol default 0.05 s     |
| rate  | higher | new < old / 1.2 (i.e. the work takes > 20 % longer)                        |
| gate  | True   | True → False (a passing gate or stage now fails)                           |

A metric present in OLD but missing in NEW is a regression too (a stage that stopped producing
it).  Timings use 20 % because the machine is shared: repeated runs of the same binary differ
by 5–15 % under load, while errors and values are deterministic (bitwise identical for any
thread count) and 1 % is already a real change.
"""
from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass

DEFAULT_ABS_TOL = {"error": 1e-5, "value": 1e-12, "time": 0.05, "rate": 0.0, "count": 0.0,
                   "gate": 0.0}
RELATIVE_NOISE = 0.01      # errors and values
TIME_FACTOR = 1.2          # timings and rates


@dataclass
class Finding:
    name: str
    kind: str
    old: object
    new: object
    verdict: str        # "regressed", "improved", "missing", "new"
    rule: str

    def line(self) -> str:
        return f"{self.verdict.upper():<9} {self.name}: {_fmt(self.old)} -> {_fmt(self.new)}  ({self.rule})"


def _fmt(v: object) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _num(v: object) -> float | None:
    if isinstance(v, bool) or v is None:
        return None
    try:
        f = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def compare_metric(name: str, old: dict, new: dict) -> Finding | None:
    kind = old.get("kind", "value")
    ov, nv = old.get("value"), new.get("value")
    tol = float(old.get("abs_tol", DEFAULT_ABS_TOL.get(kind, 0.0)))
    if kind == "gate":
        if bool(ov) and not bool(nv):
            return Finding(name, kind, ov, nv, "regressed", "gate pass -> fail")
        if not bool(ov) and bool(nv):
            return Finding(name, kind, ov, nv, "improved", "gate fail -> pass")
        return None
    o, n = _num(ov), _num(nv)
    if o is None or n is None:
        if o is not None and n is None:
            return Finding(name, kind, ov, nv, "regressed", "number became non-numeric/non-finite")
        return None
    if kind == "count":
        if o != n:
            return Finding(name, kind, o, n, "regressed", "count changed")
        return None
    if kind == "error":
        band = max(RELATIVE_NOISE * abs(o), tol)
        if n - o > band:
            return Finding(name, kind, o, n, "regressed",
                           f"error up by {n - o:.3g} > noise {band:.3g} (1 % or {tol:g})")
        if o - n > band:
            return Finding(name, kind, o, n, "improved", f"error down by {o - n:.3g}")
        return None
    if kind == "value":
        band = max(RELATIVE_NOISE * abs(o), tol)
        if abs(n - o) > band:
            return Finding(name, kind, o, n, "regressed",
                           f"value changed by {100 * (n - o) / o if o else float('inf'):+.3g} % "
                           f"> noise (1 % or {tol:g})")
        return None
    if kind == "time":
        if n > TIME_FACTOR * o and n - o > tol:
            return Finding(name, kind, o, n, "regressed",
                           f"{n / o if o else float('inf'):.2f}x slower > 1.2x")
        if o > TIME_FACTOR * n and o - n > tol:
            return Finding(name, kind, o, n, "improved", f"{o / n if n else float('inf'):.2f}x faster")
        return None
    if kind == "rate":
        if n * TIME_FACTOR < o:
            return Finding(name, kind, o, n, "regressed",
                           f"rate {n / o if o else 0:.2f}x of before (< 1/1.2)")
        if o * TIME_FACTOR < n:
            return Finding(name, kind, o, n, "improved", f"rate {n / o if o else float('inf'):.2f}x")
        return None
    return None


def compare_reports(old: dict, new: dict) -> list[Finding]:
    om, nm = old.get("metrics", {}), new.get("metrics", {})
    findings: list[Finding] = []
    for name in sorted(om):
        if name not in nm:
            findings.append(Finding(name, om[name].get("kind", "value"), om[name].get("value"),
                                    None, "missing", "metric no longer produced"))
            continue
        f = compare_metric(name, om[name], nm[name])
        if f:
            findings.append(f)
    for name in sorted(set(nm) - set(om)):
        findings.append(Finding(name, nm[name].get("kind", "value"), None, nm[name].get("value"),
                                "new", "metric not in the old report"))
    return findings


def main(old_path: str, new_path: str, out=sys.stdout) -> int:
    with open(old_path, encoding="utf-8") as f:
        old = json.load(f)
    with open(new_path, encoding="utf-8") as f:
        new = json.load(f)
    findings = compare_reports(old, new)
    bad = [f for f in findings if f.verdict in ("regressed", "missing")]
    good = [f for f in findings if f.verdict == "improved"]
    added = [f for f in findings if f.verdict == "new"]
    print(f"compare {old_path} -> {new_path}: {len(old.get('metrics', {}))} metrics before, "
          f"{len(new.get('metrics', {}))} now", file=out)
    for f in bad:
        print(f.line(), file=out)
    for f in good:
        print(f.line(), file=out)
    if added:
        print(f"({len(added)} new metrics not compared)", file=out)
    if bad:
        print(f"{len(bad)} regression(s) beyond noise", file=out)
        return 1
    print("no regression beyond noise", file=out)
    return 0
