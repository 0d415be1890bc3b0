#!/usr/bin/env python3
"""Gmsh and PETSc are plug-ins that `pd` opens on first use (libpd/include/libpd/core/plugin.hpp):
`pd` itself does not link them, a start without a mesh body does not load them, and a mesh body
still reads its mesh through the Gmsh plug-in. (The split static solve through the PETSc plug-in
is checked by the `mpi.static.*` tests.)"""
import os
import re
import shutil
import subprocess

import pdcli

MESH_SCENE = pdcli.TINY_SCENE.replace(
    "    boxes:\n      - [[0, 0, 0], [0.2, 0.03, 0]]\n", "    mesh: bar.msh\n")


def quad_mesh(nx, ny, h):
    """A .msh 2.2 file of nx × ny square quadrangles of side h in the plane z = 0."""
    nodes = [(i * h, j * h) for j in range(ny + 1) for i in range(nx + 1)]
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes", str(len(nodes))]
    lines += [f"{k + 1} {x!r} {y!r} 0" for k, (x, y) in enumerate(nodes)]
    lines += ["$EndNodes", "$Elements", str(nx * ny)]
    for j in range(ny):
        for i in range(nx):
            a = j * (nx + 1) + i + 1
            lines.append(f"{j * nx + i + 1} 3 2 1 1 {a} {a + 1} {a + nx + 2} {a + nx + 1}")
    lines += ["$EndElements"]
    return "\n".join(lines) + "\n"


class Plugins(pdcli.TestCase):
    def optional_libraries_in(self, text):
        return sorted(set(re.findall(r"lib(?:gmsh|petsc)[\w.]*\.so[\w.]*", text)))

    def test_pd_links_neither_gmsh_nor_petsc(self):
        readelf = shutil.which("readelf")
        if readelf is None:
            self.skipTest("readelf is not installed")
        r = subprocess.run([readelf, "-d", pdcli.PD], capture_output=True, text=True, check=True)
        needed = "\n".join(line for line in r.stdout.splitlines() if "(NEEDED)" in line)
        self.assertTrue(needed, r.stdout)
        self.assertEqual(self.optional_libraries_in(needed), [], needed)

    def test_a_start_without_mesh_bodies_loads_no_plugin(self):
        env = dict(os.environ, LD_DEBUG="files")
        for args in (["--help"], ["info", self.scene()]):
            r = self.pd(*args, env=env)
            self.assertEqual(r.returncode, 0, r.stderr[-2000:])
            self.assertIn("calling init", r.stderr)  # LD_DEBUG took effect
            self.assertEqual(self.optional_libraries_in(r.stderr), [], args)
            self.assertNotIn("libpd_gmsh", r.stderr)
            self.assertNotIn("libpd_petsc", r.stderr)

    def test_a_mesh_body_is_read_through_the_gmsh_plugin(self):
        with open(self.path("bar.msh"), "w", encoding="utf-8") as f:
            f.write(quad_mesh(20, 3, 0.01))
        scene = self.scene(text=MESH_SCENE.format(
            effects="damping", integrator="damped-euler", dt="auto", end_time="2e-4",
            solver_extra="  damping: 1e6\n", vtu="false", vtu_every=100))
        r = self.pd("info", scene, env=dict(os.environ, LD_DEBUG="files"))
        self.assertEqual(r.returncode, 0, r.stderr[-2000:])
        self.assertIn("libpd_gmsh.so", r.stderr)
        self.assertNotIn("libpd_petsc", r.stderr)
        # One particle per quadrangle (60), and the ghost sites around them: the quadrangles are
        # lattice cells, so as many as the estimate counts around the bar's box.
        m = re.search(r"particles +(\d+) +(\d+)", r.stdout)
        self.assertIsNotNone(m, r.stdout)
        self.assertGreater(int(m.group(1)), 60, r.stdout)
        self.assertEqual(m.group(1), m.group(2), r.stdout)


if __name__ == "__main__":
    pdcli.main()
