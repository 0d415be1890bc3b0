#!/usr/bin/python3
"""Checkpoint/restart end to end: a `pd run` killed with SIGKILL mid-way and restarted from its last
checkpoint must end bitwise identical to a run that was never stopped.

    kill_restart_test.py PD SCENE VARIANT WORKDIR

VARIANT picks the integrator (the scene is dogbone.yaml with the solver lines replaced):
damped-euler, verlet and adr run with damage (bonds break in the neck before and after the
checkpoint the restart starts from), arkode-rk4 (#311 work-around: ERKStep reset every step)
without it, since arkode refuses damage. damped-euler-sigint stops the run with SIGINT instead
(Ctrl-C): without --checkpoint-every, the checkpoint written on the interrupt must suffice.

Three runs: A uninterrupted; B killed (SIGKILL, no chance to clean up) once it has written the VTU
frame `kill_at` (so at least one checkpoint exists and the kill lands between checkpoints); B
restarted from B's checkpoint into the same folder. An arkode variant exits with 77 (skipped) if pd
was built without SUNDIALS. Then every file of A and B must be
byte-identical (the final checkpoints hold every bit of state: positions, velocities, forces, bond
history, integrator internals, counters and the probe history; probes.csv and the VTU files are
their text images), except summary.json, where only the wall-clock fields, the checkpoint path and
`restarted_from` may differ.
"""
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

# Per variant: the solver block, the effects, whether bonds break, steps between checkpoints and
# between VTU frames, the VTU frame after which the run is killed (not a checkpoint step, so the
# kill lands between checkpoints and the restart recomputes steps) and (end_time, ramp_time) if
# the run is shortened. Bonds break in the dynamic runs from step ~2500 to ~5500 and in ADR's
# quasi-static one in a burst at steps 2200-2225: each restart starts with some bonds broken and
# breaks more.
DAMPED = "  integrator: damped-euler\n  dt: auto\n  safety: 0.8\n  damping: 1e7\n"
VARIANTS = {
    "damped-euler": dict(solver=DAMPED, effects="[damage, damping]", damage=True,
                         checkpoint_every=1000, vtu_every=500, kill_at=3500),
    "verlet": dict(solver="  integrator: verlet\n  dt: auto\n  safety: 0.8\n",
                   effects="[damage]", damage=True, checkpoint_every=1000, vtu_every=500,
                   kill_at=3500),
    "adr": dict(solver="  integrator: adr\n  dt: auto\n  safety: 0.8\n", effects="[damage]",
                damage=True, checkpoint_every=200, vtu_every=100, kill_at=2300),
    # Four force evaluations per step: a shorter run. The #311 work-around resets ERKStep before
    # every step; the FSAL tables are covered by checkpoint_test (in-process, smaller).
    "arkode-rk4": dict(solver="  integrator: arkode\n  arkode:\n    table: rk4\n  dt: auto\n"
                       "  safety: 0.8\n  damping: 1e7\n", effects="[damping]", damage=False,
                       checkpoint_every=250, vtu_every=125, kill_at=375, times=("5e-4", "4e-4")),
    "damped-euler-sigint": dict(solver=DAMPED, effects="[damage, damping]", damage=True,
                                checkpoint_every=1000, vtu_every=500, kill_at=3500,
                                signal=signal.SIGINT),
}

# Fields of summary.json that legitimately differ between the two runs.
VOLATILE = {"wall_seconds", "bond_updates_per_second", "setup_seconds", "setup", "solve_seconds",
            "peak_memory_bytes", "checkpoint", "threads",
            "force_evaluations_this_run", "stop_signal",
            "restarted_from"}


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def make_scene(template, variant, path):
    v = VARIANTS[variant]
    text = open(template).read()
    text, n = re.subn(r"  integrator: damped-euler\n  dt: auto\n  safety: 0.8\n  damping: 1e7\n",
                      v["solver"], text)
    if n != 1:
        fail("the scene template no longer has the expected solver block")
    text = text.replace("effects: [damage, damping]", f"effects: {v['effects']}")
    text = text.replace("vtu_every: 500", f"vtu_every: {v['vtu_every']}")
    if not v["damage"]:
        text = text.replace("    critical_stretch: 1e-3\n", "")
    if "times" in v:
        text = text.replace("  ramp_time: 2e-3\n  end_time: 3e-3\n",
                            f"  ramp_time: {v['times'][1]}\n  end_time: {v['times'][0]}\n")
    open(path, "w").write(text)


def run(pd, args, env):
    p = subprocess.run([pd, "run", *args], env=env, capture_output=True, text=True, timeout=300)
    if p.returncode != 0 and "SUNDIALS" in p.stderr:
        print(f"SKIP: {p.stderr.strip()}")
        sys.exit(77)
    if p.returncode != 0:
        fail(f"pd run {' '.join(args)} exited with {p.returncode}:\n{p.stdout}\n{p.stderr}")
    return p.stdout


def files(folder):
    # .pd-lock holds the pid of the run that last held the folder: not a result.
    return sorted(f for f in os.listdir(folder) if ".tmp-" not in f and f != ".pd-lock")


def damage_mean(vtu):
    text = open(vtu).read()
    block = text.split('Name="damage" format="ascii">\n')[1].split("</DataArray>")[0]
    values = [float(v) for v in block.split()]
    return sum(values) / len(values)


def compare_outputs(a, b, fa, resumed):
    """Every file of the uninterrupted run (folder a) equals the restarted run's (folder b), up to
    the summary's volatile fields and the interrupted run's last frame in the manifest."""
    for f in fa:
        pa, pb = os.path.join(a, f), os.path.join(b, f)
        if f == "summary.json":
            ja, jb = json.load(open(pa)), json.load(open(pb))
            if jb.get("restarted_from", {}).get("step") != resumed:
                fail(f"summary.json of the restart lacks restarted_from.step = {resumed}")
            ja = {k: v for k, v in ja.items() if k not in VOLATILE}
            jb = {k: v for k, v in jb.items() if k not in VOLATILE}
            if ja != jb:
                diff = {k: (ja.get(k), jb.get(k)) for k in set(ja) | set(jb)
                        if ja.get(k) != jb.get(k)}
                fail(f"summary.json differs: {diff}")
        elif f == "manifest.txt":
            # It lists every file in the folder, so also the interrupted run's last frame.
            la = open(pa).read().splitlines()
            lb = [l for l in open(pb).read().splitlines()
                  if l in la or l != f"particles-{resumed:08d}.vtu"]
            if la != lb:
                fail(f"manifest.txt differs: {sorted(set(la) ^ set(lb))}")
        elif open(pa, "rb").read() != open(pb, "rb").read():
            fail(f"{f} differs between the uninterrupted and the restarted run")


def check_damage_grows(a, fa, resumed):
    """Fails unless bonds broke both before and after the restart step (run a's frames)."""
    # The restart must have carried bond history and continued to break bonds after it.
    frames = sorted(f for f in fa if f.startswith("particles-") and f.endswith(".vtu"))
    step_of = lambda f: int(f[len("particles-"):-len(".vtu")])
    before = [f for f in frames if step_of(f) <= resumed][-1]
    d_before, d_end = damage_mean(os.path.join(a, before)), damage_mean(os.path.join(a, frames[-1]))
    if not (0 < d_before < d_end):
        fail(f"damage should grow across the restart: mean φ {d_before} at {before}, "
             f"{d_end} at the end (change the scene so bonds break before and after step "
             f"{resumed})")
    print(f"mean damage {d_before:.5f} at {before}, {d_end:.5f} at the end")


def main():
    if len(sys.argv) != 5:
        fail(__doc__)
    pd, template, variant, work = sys.argv[1:]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    scene = os.path.join(work, f"{variant}.yaml")
    make_scene(template, variant, scene)
    a, b = os.path.join(work, "a"), os.path.join(work, "b")
    every = VARIANTS[variant]["checkpoint_every"]
    common = [scene, "--checkpoint-every", str(every)]

    t0 = time.monotonic()
    out_a = run(pd, [*common, "-o", a], env)
    steps = int(re.search(r"(\d+) steps of", out_a).group(1))
    t_a = time.monotonic() - t0

    sig = VARIANTS[variant].get("signal", signal.SIGKILL)
    kill_at = VARIANTS[variant]["kill_at"]
    if not (every < kill_at < steps and kill_at % every != 0):
        fail(f"kill_at {kill_at} must lie between checkpoints, after the first, in {steps} steps")
    marker = os.path.join(b, f"particles-{kill_at:08d}.vtu")
    killed_args = [*common, "-o", b] if sig == signal.SIGKILL else [scene, "-o", b]
    proc = subprocess.Popen([pd, "run", *killed_args], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    while not os.path.exists(marker):
        if proc.poll() is not None:
            fail(f"the run to be killed ended (exit {proc.returncode}) before writing {marker}")
        time.sleep(0.002)
    proc.send_signal(sig)
    killed_out = proc.communicate()[0]
    ckpt = os.path.join(b, "checkpoint.pdcp")
    if sig == signal.SIGKILL:
        if proc.returncode != -signal.SIGKILL:
            fail(f"the run ended by itself (exit {proc.returncode}) before SIGKILL: make it longer")
        if os.path.exists(os.path.join(b, "summary.json")):
            fail("the killed run wrote summary.json: it was not killed mid-way")
    else:
        status = json.load(open(os.path.join(b, "summary.json")))["status"]
        if status != "interrupted":
            fail(f"after SIGINT the run's status is '{status}', not 'interrupted': make it longer")
        if f"--restart {ckpt}" not in killed_out:
            fail(f"the interrupted run did not say how to resume:\n{killed_out}")
    if not os.path.exists(ckpt):
        fail("no checkpoint after the kill")

    out_b = run(pd, [*common, "-o", b, "--restart", ckpt], env)
    m = re.search(r"restarted from .* at step (\d+)", out_b)
    if not m:
        fail(f"the restart did not report its step:\n{out_b}")
    resumed = int(m.group(1))
    if sig == signal.SIGKILL and not (0 < resumed <= kill_at and resumed % every == 0):
        fail(f"restarted at step {resumed}; expected a checkpoint step in (0, {kill_at}]")
    if sig == signal.SIGINT and not kill_at <= resumed < steps:
        fail(f"restarted at step {resumed}; the interrupt came after step {kill_at}")

    fa, fb = files(a), files(b)
    if sig == signal.SIGINT:
        # The interrupted run wrote its last state as a final VTU frame, which the restarted run's
        # particles.pvd (compared below) rightly does not list.
        fb = [f for f in fb if f != f"particles-{resumed:08d}.vtu" or f in fa]
    if fa != fb:
        fail(f"different files:\n  uninterrupted {fa}\n  restarted     {fb}")
    compare_outputs(a, b, fa, resumed)

    if VARIANTS[variant]["damage"]:
        check_damage_grows(a, fa, resumed)
    print(f"{variant}: {steps} steps, {signal.Signals(sig).name} after step {kill_at}, "
          f"restarted at step {resumed}; "
          f"{len(fa)} files identical (uninterrupted run {t_a:.2f} s)")
    print("PASS")


if __name__ == "__main__":
    main()
