"""The report's mesh-setup stage (issue 39): the set-up time and memory of a part drawn in CAD,
meshed by Gmsh and filled with about a million lattice sites (`--full` only)."""
from __future__ import annotations

import json
import time

from . import records as R
from .fmt import esc, fnum
from .markup import failed_box, num_td, table
from .page import Page
from .stages import Ctx, Stage, StageFailed, _loadavg, run

MESH_SETUP_SCENE = "verification/scenes/benchmarks/mesh-body-benchmark.yaml"


def mesh_setup_stage(ctx: Ctx) -> Stage:
    scene = ctx.root / MESH_SETUP_SCENE
    out = ctx.work / "mesh-setup"
    cmd = [str(ctx.pd), "run", str(scene), "-o", str(out), "--overwrite"]

    def fn(ctx: Ctx, st: Stage) -> dict:
        load_before = _loadavg()
        start = time.monotonic()
        run(ctx, cmd, "mesh-setup")
        wall = time.monotonic() - start
        try:
            summary = json.loads((out / "summary.json").read_text())
        except (OSError, json.JSONDecodeError) as e:
            raise StageFailed(f"no summary.json from the mesh body's run: {e}") from e
        keep = ("particles", "bonds", "bonds_per_particle", "setup_seconds", "setup",
                "memory_bytes", "peak_memory_bytes")
        return {"scene": MESH_SETUP_SCENE, "wall_seconds": wall, "loadavg_before": load_before,
                "loadavg_after": _loadavg(), **{k: summary.get(k) for k in keep}}

    return Stage("mesh-setup", "bench", "set-up of a million-particle CAD part", [cmd],
                 [ctx.pd, scene, scene.with_suffix(".geo")], fn, default_seconds=150)


def mesh_setup_block(page: Page) -> str:
    rec = page.rec.get("mesh-setup")
    if rec is None:
        return '<p class="note">Not run: the mesh-setup stage runs with <code>--full</code>.</p>'
    if not R.ok(rec):
        return failed_box(rec, "the mesh-setup stage")
    r = rec["result"]
    setup = r.get("setup") or {}
    parts = [setup.get(k) for k in ("scene_seconds", "model_seconds", "simulation_seconds")]
    total = sum(parts) if all(isinstance(p, (int, float)) for p in parts) else None
    mib = 1024.0 * 1024.0
    row = [num_td(fnum(r.get("particles"))), num_td(fnum(r.get("bonds"))),
           num_td(fnum(parts[0], 3)), num_td(fnum(parts[1], 3)), num_td(fnum(parts[2], 3)),
           num_td(fnum(total, 3)),
           num_td(fnum((r.get("memory_bytes") or 0) / mib, 4)),
           num_td(fnum((r.get("peak_memory_bytes") or 0) / mib, 4))]
    return (f'<p class="note"><code>pd run {esc(r["scene"])}</code> (pd\'s default threads): the '
            "part of its <code>.geo</code> file meshed by Gmsh with unstructured tetrahedra at the "
            "lattice spacing and filled with the lattice sites inside them (the default for a "
            "geometry file), one explicit step. Scene: reading the scene, meshing, locating the "
            "sites; model: families, weights, ghost layers; simulation: the integrator's set-up. "
            f'Load average before {esc(r.get("loadavg_before"))}, after '
            f'{esc(r.get("loadavg_after"))}.</p>' +
            table(["particles", "bonds", "scene (s)", "model (s)", "simulation (s)",
                   "set-up in all (s)", "model memory (MiB)", "peak memory (MiB)"], [row],
                  'id="mesh-setup-table"'))
