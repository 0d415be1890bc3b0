#!/usr/bin/env python3
"""Compare two pd runs of the same scene bit for bit, whatever rank counts wrote them.

    compare_runs.py DIR_A DIR_B

Compares summary.json's numbers (status, steps, time, Δt, energies, residual, probes),
probes.csv, and every VTU frame listed in particles.pvd (a .vtu, or a .pvtu with its pieces)
joined on the particles' `global_id`. pd writes numbers in the shortest form that reads back to
the same double, so equal text is equal bits. Exit 1 and name every difference.
"""
from __future__ import annotations

import json
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

SUMMARY_KEYS = ["status", "steps", "time", "dt", "dt_stable", "kinetic_energy", "strain_energy",
                "residual", "force_evaluations", "probes", "particles", "bonds"]


def summary(d: Path) -> dict:
    s = json.loads((d / "summary.json").read_text())
    return {k: s.get(k) for k in SUMMARY_KEYS}


def arrays(vtu: Path) -> dict[str, list[str]]:
    """Per named point array (and the points), the values of each particle as text."""
    root = ET.parse(vtu).getroot()
    out: dict[str, list[str]] = {}
    piece = root.find("UnstructuredGrid/Piece")
    points = piece.find("Points/DataArray")
    out["points"] = points.text.split("\n")
    for a in piece.findall("PointData/DataArray"):
        out[a.get("Name")] = a.text.split("\n")
    return {k: [line for line in v if line.strip()] for k, v in out.items()}


def frame(path: Path) -> dict[int, dict[str, str]]:
    """Particle global_id → {array: text}, over all pieces of a frame."""
    files = [path]
    if path.suffix == ".pvtu":
        root = ET.parse(path).getroot()
        files = [path.parent / p.get("Source") for p in root.iter("Piece")]
    rows: dict[int, dict[str, str]] = {}
    for f in files:
        a = arrays(f)
        for k, gid in enumerate(a["global_id"]):
            g = int(gid)
            if g in rows:
                raise SystemExit(f"{f}: particle {g} written twice")
            rows[g] = {name: values[k] for name, values in a.items() if name != "global_id"}
    return rows


def frames(d: Path) -> list[tuple[str, Path]]:
    pvd = d / "particles.pvd"
    if not pvd.exists():
        return []
    root = ET.parse(pvd).getroot()
    return [(ds.get("timestep"), d / ds.get("file")) for ds in root.iter("DataSet")]


def main() -> int:
    a, b = Path(sys.argv[1]), Path(sys.argv[2])
    problems: list[str] = []
    sa, sb = summary(a), summary(b)
    for k in SUMMARY_KEYS:
        if sa[k] != sb[k]:
            problems.append(f"summary.json {k}: {sa[k]!r} vs {sb[k]!r}")
    pa, pb = (a / "probes.csv"), (b / "probes.csv")
    if pa.exists() or pb.exists():
        if pa.read_text() != pb.read_text():
            problems.append("probes.csv differs")
    fa, fb = frames(a), frames(b)
    if [t for t, _ in fa] != [t for t, _ in fb]:
        problems.append(f"VTU frame times differ: {[t for t, _ in fa]} vs {[t for t, _ in fb]}")
    compared = 0
    for (t, x), (_, y) in zip(fa, fb):
        rx, ry = frame(x), frame(y)
        if rx.keys() != ry.keys():
            problems.append(f"frame t={t}: different particles ({len(rx)} vs {len(ry)})")
            continue
        bad = [g for g in rx if rx[g] != ry[g]]
        if bad:
            g = bad[0]
            problems.append(f"frame t={t}: {len(bad)} particles differ, e.g. #{g}: {rx[g]} vs {ry[g]}")
        compared += len(rx)
    for p in problems:
        print("DIFFERENT:", p)
    if not problems:
        print(f"identical: summary, probes.csv, {len(fa)} VTU frames ({compared} particle rows) "
              f"of {a} and {b}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
