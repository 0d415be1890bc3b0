"""`pd run` must not destroy files, mix runs, lose results or lie about them (issue 18, items 1,
4, 5, 6 and 8). Each test names the defect it guards; all of them failed before the fix.
"""
import json
import os
import re
import signal
import subprocess
import time

import pdcli

LONG = "50.0"  # end_time of a run that takes minutes: stopped by the test


def read_json(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def stop(p):
    if p.poll() is None:
        p.kill()
    p.communicate()


class RunSafety(pdcli.TestCase):
    def start_long_run(self, out, *extra):
        scene = self.scene("long.yaml", end_time=LONG)
        p = subprocess.Popen([pdcli.PD, "run", scene, "-o", out, *extra], cwd=self.dir,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.addCleanup(stop, p)
        deadline = time.monotonic() + 20
        while not os.path.exists(os.path.join(out, "manifest.txt")):  # the run has started
            self.assertIsNone(p.poll(), p.stderr.read() if p.poll() is not None else "")
            self.assertLess(time.monotonic(), deadline, "the run never wrote its manifest")
            time.sleep(0.05)
        time.sleep(0.3)
        return p

    # Item 1: --checkpoint PATH overwrote whatever was at PATH.
    def test_checkpoint_never_replaces_a_scene_file(self):
        scene = self.scene()
        before = open(scene, "rb").read()
        r = self.pd("run", scene, "-o", self.path("out"), "--checkpoint", scene)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("not a libpd checkpoint", r.stderr)
        self.assertEqual(open(scene, "rb").read(), before)

    def test_checkpoint_never_replaces_a_fifo_or_device(self):
        fifo = self.path("fifo")
        os.mkfifo(fifo)
        r = self.pd("run", self.scene(), "-o", self.path("out"), "--checkpoint", fifo)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("not a regular file", r.stderr)
        if os.geteuid() == 0:  # as root the old pd replaced /dev/null with a regular file
            r = self.pd("run", self.scene(), "-o", self.path("out2"), "--checkpoint", "/dev/null")
            self.assertEqual(r.returncode, 1, r.stderr)
            self.assertTrue(os.path.exists("/dev/null") and not os.path.isfile("/dev/null"))

    def test_checkpoint_never_onto_the_runs_own_outputs(self):
        out = self.path("out")
        r = self.pd("run", self.scene(), "-o", out, "--checkpoint", os.path.join(out, "summary.json"))
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("a file the run itself writes", r.stderr)

    # Item 4: two runs into one folder mixed their files; a rerun left the old run's files.
    def test_second_run_into_a_busy_folder_is_refused(self):
        out = self.path("out")
        first = self.start_long_run(out)
        r = self.pd("run", self.scene(), "-o", out, "--overwrite")
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("in use by another pd run", r.stderr)
        self.assertIn(str(first.pid), r.stderr)

    def test_rerun_refuses_then_overwrite_removes_exactly_the_old_files(self):
        out = self.path("out")
        scene = self.scene(vtu="true", vtu_every=50)
        self.assertEqual(self.pd("run", scene, "-o", out).returncode, 0)
        old = set(os.listdir(out))
        self.assertIn("particles-00000050.vtu", old)
        with open(os.path.join(out, "notes.txt"), "w") as f:
            f.write("mine")
        r = self.pd("run", scene, "-o", out)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("--overwrite", r.stderr)
        # The rerun writes fewer frames (a step limit, whatever Δt the model gets): none of the
        # old ones may survive beside it.
        scene2 = self.scene("short.yaml", solver_extra="  damping: 1e6\n  max_steps: 60\n",
                            vtu="true", vtu_every=50)
        r = self.pd("run", scene2, "-o", out, "--overwrite")
        self.assertEqual(r.returncode, 0, r.stderr)
        now = set(os.listdir(out))
        self.assertIn("notes.txt", now)
        self.assertNotIn("particles-00000100.vtu", now)
        listed = set(open(os.path.join(out, "manifest.txt")).read().split("\n")[1:]) - {""}
        self.assertEqual(now - {"notes.txt", ".pd-lock", "manifest.txt"}, listed)

    def test_files_without_a_manifest_are_never_removed(self):
        out = self.path("out")
        os.makedirs(out)
        with open(os.path.join(out, "summary.json"), "w") as f:
            f.write("{}")
        r = self.pd("run", self.scene(), "-o", out, "--overwrite")
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertEqual(open(os.path.join(out, "summary.json")).read(), "{}")

    # Item 5: an unwritable folder was found only after the run.
    def test_unwritable_output_is_refused_before_the_run(self):
        blocker = self.path("a-file")
        open(blocker, "w").close()
        t0 = time.monotonic()
        scene = self.scene("long.yaml", end_time=LONG)
        r = self.pd("run", scene, "-o", os.path.join(blocker, "sub"))
        self.assertEqual(r.returncode, 1, r.stderr)
        # The run would take minutes: refusing it within a minute means before it ran.
        self.assertLess(time.monotonic() - t0, 60, "refused only after running")
        self.assertRegex(r.stderr, "Not a directory|File exists")

    # Item 6: SIGTERM and SIGHUP killed the run without checkpoint or summary; exit was 0.
    def test_sigterm_and_sighup_stop_cleanly_with_exit_5(self):
        for sig in (signal.SIGTERM, signal.SIGHUP, signal.SIGINT):
            out = self.path(f"out-{sig.name}")
            p = self.start_long_run(out)
            p.send_signal(sig)
            _, err = p.communicate(timeout=30)
            self.assertEqual(p.returncode, 5, f"{sig.name}: {err}")
            summary = read_json(os.path.join(out, "summary.json"))
            self.assertEqual(summary["status"], "interrupted")
            self.assertEqual(summary["stop_signal"], int(sig))
            self.assertTrue(os.path.exists(os.path.join(out, "checkpoint.pdcp")), sig.name)

    # Item 8: a restart divided all evaluations by the wall time since the restart.
    def test_throughput_after_restart_counts_this_run_only(self):
        out = self.path("out")
        scene = self.scene(end_time="2e-3")
        first = self.pd("run", scene, "-o", out, "--checkpoint-every", "100")
        self.assertEqual(first.returncode, 0, first.stderr)
        rate0 = read_json(os.path.join(out, "summary.json"))["bond_updates_per_second"]
        r = self.pd("run", scene, "-o", out, "--restart", os.path.join(out, "checkpoint.pdcp"))
        self.assertEqual(r.returncode, 0, r.stderr)
        s = read_json(os.path.join(out, "summary.json"))
        self.assertEqual(s["force_evaluations_this_run"], 0)  # it was finished already
        self.assertLessEqual(s["bond_updates_per_second"], max(10 * rate0, 1e10))


    # Item 2 (first part): an explicit Δt above the eq. 31 limit ran silently to end_time.
    def test_explicit_dt_above_the_limit_is_a_warning(self):
        r = self.pd("info", self.scene())
        limit = float(re.search(r"stable dt \(eq. 31\)\s+(\S+)", r.stdout).group(1))
        scene = self.scene("fast.yaml", integrator="verlet", effects="", dt=f"{1.23 * limit:.6g}",
                           end_time=f"{10 * limit:.6g}", solver_extra="")
        out = self.path("out")
        r = self.pd("run", scene, "-o", out)
        self.assertRegex(r.stderr, r"warning: solver.dt = .* is 1.23× the stable limit")
        warnings = read_json(os.path.join(out, "summary.json")).get("warnings", [])
        self.assertTrue(any("stable limit" in w for w in warnings), warnings)


    # Item 2 (second part): the shipped bar at 1.23× eq. 31 with a short end_time ran to
    # end_time, exit 0, with 85,679 J of kinetic energy (the stable run: 0.0227 J): the
    # displacements had not yet left the bounding box. Instability is found from the energy.
    def test_instability_is_found_from_energy_not_left_as_end_time(self):
        shipped = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                               "verification", "cases", "bar-vibration", "bar-vibration.yaml")
        with open(shipped, encoding="utf-8") as f:
            text = f.read()
        limit = float(re.search(r"stable dt \(eq. 31\)\s+(\S+)",
                                self.pd("info", shipped).stdout).group(1))
        for factor, code in ((1.23, 3), (0.9, 0)):
            scene_text = re.sub(r"\n  dt: [^\n]*", f"\n  dt: {factor * limit:.6g}", text)
            scene_text = re.sub(r"\n  end_time: [^\n]*", f"\n  end_time: {120 * limit:.6g}",
                                scene_text)
            out = self.path(f"out-{factor}")
            r = self.pd("run", self.scene(f"bar-{factor}.yaml", text=scene_text), "-o", out)
            self.assertEqual(r.returncode, code, f"{factor}× the limit: {r.stderr}")
            if code == 3:
                self.assertRegex(r.stderr, r"kinetic energy \S+ J is \S+× the energy put in")
                self.assertIn("lower solver.dt", r.stderr)
                self.assertEqual(read_json(os.path.join(out, "summary.json"))["status"],
                                 "unstable")

if __name__ == "__main__":
    pdcli.main()
