"""`pd run` never writes through a link it did not make (issue 38, items 1 and 2): a symbolic
link planted in the output folder under a name the run writes, or under a temporary name it
would have used, never lets the run change a file outside the folder. And a path it could not
write, or not read back, is refused before the run (item 3). Each test failed before the fix
(the lock, the manifest, summary.json and checkpoints were opened through links; a folder path
near PATH_MAX was claimed and found too long only when the run wrote into it).
"""
import os

import pdcli

PATH_MAX = os.pathconf("/", "PC_PATH_MAX")

KEEP = "KEEP: a file outside the output folder\n"

# Every name the tiny scene's run writes with VTU frames and checkpoints on.
RUN_NAMES = [".pd-lock", "manifest.txt", "summary.json", "probes.csv", "particles.pvd",
             "particles-00000000.vtu", "checkpoint.pdcp"]


class FileSafety(pdcli.TestCase):
    def run_args(self, out):
        scene = self.scene(vtu="true", vtu_every=10)
        return ["run", scene, "-o", out, "--checkpoint-every", "10"]

    def target(self, name):
        """A file outside the output folder that a planted link points at."""
        p = self.path("outside-" + name.strip("."))
        with open(p, "w", encoding="utf-8") as f:
            f.write(KEEP)
        return p

    def assert_unchanged(self, targets):
        for t in targets:
            with open(t, encoding="utf-8") as f:
                self.assertEqual(f.read(), KEEP, f"{t} was written through a link")

    # Item 1: a link under a run file's name was followed (.pd-lock: the target got the pid).
    def test_a_folder_with_links_under_run_names_is_refused(self):
        for name in RUN_NAMES:
            with self.subTest(name=name):
                out = self.path("out-" + name.strip("."))
                os.makedirs(out)
                t = self.target(name)
                os.symlink(t, os.path.join(out, name))
                r = self.pd(*self.run_args(out))
                self.assertEqual(r.returncode, 1, f"{name}: {r.stderr}")
                self.assertIn("symbolic link", r.stderr)
                self.assertIn(name, r.stderr)
                self.assert_unchanged([t])

    def test_a_hard_linked_lock_is_refused(self):
        out = self.path("out")
        os.makedirs(out)
        t = self.target("lock")
        os.link(t, os.path.join(out, ".pd-lock"))
        r = self.pd(*self.run_args(out))
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("hard link", r.stderr)
        self.assert_unchanged([t])

    # Item 2: temporary names were NAME.tmp-PID, opened through a link planted there.
    def test_links_under_the_old_temporary_names_are_never_followed(self):
        out = self.path("out")
        os.makedirs(out)
        targets = {name: self.target("tmp-" + name) for name in RUN_NAMES}

        def plant():  # in the child, just before exec: os.getpid() is pd's pid
            for name, t in targets.items():
                os.symlink(t, os.path.join(out, f"{name}.tmp-{os.getpid()}"))

        r = self.pd(*self.run_args(out), preexec_fn=plant)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assert_unchanged(targets.values())
        for name in ("manifest.txt", "summary.json", "probes.csv", "particles.pvd",
                     "checkpoint.pdcp"):
            p = os.path.join(out, name)
            self.assertTrue(os.path.isfile(p) and not os.path.islink(p), name)
        # The run's own temporaries are all renamed into place; only the planted links remain.
        strays = [f for f in os.listdir(out) if ".tmp-" in f and not os.path.islink(
            os.path.join(out, f))]
        self.assertEqual(strays, [])

    def long_path(self, length):
        """A path of `length` characters under the scratch folder, in components of 200."""
        parts, total = [], len(self.dir)
        while total + 1 + 200 < length:
            parts.append("d" * 200)
            total += 201
        parts.append("e" * (length - total - 1))
        p = os.path.join(self.dir, *parts)
        self.assertEqual(len(p), length)
        return p

    # Item 3: a 4,080-character -o was claimed, ran, then failed with "File name too long".
    def test_paths_near_path_max_are_refused_before_the_run(self):
        out = self.long_path(PATH_MAX - 16)
        r = self.pd(*self.run_args(out))
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("the output folder (-o) is", r.stderr)
        self.assertIn("PATH_MAX", r.stderr)
        self.assertFalse(os.path.exists(os.path.dirname(out)), "the folder was claimed")
        ckpt = self.long_path(PATH_MAX - 16)
        r = self.pd(*self.run_args(self.path("out")), "--checkpoint", ckpt)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("the checkpoint path is", r.stderr)
        self.assertFalse(os.path.exists(self.path("out", "summary.json")))
        # A --restart path too long to open is an error message, not an abort.
        r = self.pd("run", self.scene(), "-o", self.path("out2"), "--restart", ckpt + "x" * 16)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("File name too long", r.stderr)


if __name__ == "__main__":
    pdcli.main()
