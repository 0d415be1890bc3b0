#!/usr/bin/python3
"""Runs split over MPI ranks give the same bits as one process.

    mpi_test.py ranks PD MPIEXEC SCENE WORKDIR N1,N2,...
        run SCENE on each rank count and compare every run with the first (compare_runs.py):
        summary numbers, probes.csv and every VTU frame joined on global_id.
    mpi_test.py kill-restart PD MPIEXEC SCENE WORKDIR N
        on N ranks: run A uninterrupted; run B killed with SIGKILL (the whole process group,
        mpiexec and every rank) between two checkpoints, then restarted from its checkpoint
        pieces; A and B must be identical, and so must their checkpoint pieces, byte for byte.
    mpi_test.py errors PD MPIEXEC SCENE WORKDIR N
        on N ranks (issue 38, items 5 and 6): the restart command a run prints works as
        printed; with one rank's checkpoint piece deleted, the restart ends the whole job with
        that rank's message (exit 1) instead of leaving the other ranks waiting forever.
    mpi_test.py set-recovery PD MPIEXEC SCENE WORKDIR N
        on N ranks (issue 38, item 4): a checkpoint set left half-replaced by a killed rank is
        restartable. The two states a kill can leave are laid out exactly: killed while the new
        pieces were written (the older set must be used) and killed while they were renamed into
        place (the newer set must be finished); either restart must end as the run never
        stopped. SCENE must end at step 900 (fracture-adr.yaml).
    mpi_test.py stop PD MPIEXEC SCENE WORKDIR N
        on N ranks (issue 38, item 11): a stop request sent to mpirun. SIGUSR1, which OpenMPI
        forwards to every rank, ends the job with the run's exit 5, an interrupted summary and a
        complete checkpoint set that restarts. SIGTERM is mpirun's own abort (exit 1 whatever
        the ranks return, SIGKILL one second after it signals them): every rank must still have
        stopped cleanly within that second, with the same files. SCENE runs far longer than the
        test waits (its end_time is raised).
    mpi_test.py rank-change PD MPIEXEC SCENE WORKDIR N:M,...
        (issue 40): for each pair, the scene ended at step 600 on N ranks, its checkpoint set
        restarted on M ranks to the end; the result must equal an uninterrupted run bit for
        bit. SCENE must end at step 900 (fracture-adr.yaml), with bonds broken before 600.

MPIEXEC may carry options ("mpiexec --oversubscribe"); as root, --allow-run-as-root is added.
"""
import json
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import compare_runs

HERE = Path(__file__).resolve().parent


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def launcher(mpiexec, n):
    cmd = shlex.split(mpiexec)
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    return [*cmd, "-np", str(n)]


def pd_run(pd, mpiexec, n, scene, out, extra=()):
    cmd = [*launcher(mpiexec, n), pd, "run", scene, "-o", str(out), "--threads", "1", *extra]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                       env=dict(os.environ, OMP_NUM_THREADS="1"))
    if p.returncode != 0:
        fail(f"{' '.join(cmd)} exited with {p.returncode}:\n{p.stdout}\n{p.stderr}")
    return p.stdout


def compare(a, b):
    p = subprocess.run([sys.executable, str(HERE / "compare_runs.py"), str(a), str(b)],
                       capture_output=True, text=True)
    print(p.stdout.strip())
    if p.returncode != 0:
        fail(f"{a} and {b} differ")


def ranks(pd, mpiexec, scene, work, counts):
    runs = []
    for n in counts:
        out = work / f"np{n}"
        t0 = time.monotonic()
        pd_run(pd, mpiexec, n, scene, out)
        print(f"{n} rank(s): {time.monotonic() - t0:.1f} s")
        runs.append(out)
    for other in runs[1:]:
        compare(runs[0], other)


def descendants(pid):
    """pid and every process below it (mpiexec puts its ranks in process groups of their own)."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        try:
            children = Path(f"/proc/{p}/task/{p}/children").read_text().split()
        except OSError:
            children = []
        todo.extend(int(c) for c in children)
    return out


def kill_all(pid):
    for p in descendants(pid):
        try:
            os.kill(p, signal.SIGKILL)
        except ProcessLookupError:
            pass


def kill_restart(pd, mpiexec, scene, work, n):
    every, kill_frame = "100", "particles-00000150.pvtu"
    a, b = work / "a", work / "b"
    pd_run(pd, mpiexec, n, scene, a, ["--checkpoint-every", every])
    cmd = [*launcher(mpiexec, n), pd, "run", scene, "-o", str(b), "--threads", "1",
           "--checkpoint-every", every]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    deadline = time.monotonic() + 300
    while not (b / kill_frame).exists():
        if proc.poll() is not None:
            fail(f"run B ended (exit {proc.returncode}) before {kill_frame} appeared:\n"
                 f"{proc.stderr.read()}")
        if time.monotonic() > deadline:
            kill_all(proc.pid)
            fail(f"{kill_frame} did not appear")
        time.sleep(0.002)
    kill_all(proc.pid)  # mpiexec and every rank, no chance to clean up
    proc.wait()
    time.sleep(0.5)  # the ranks' lock on the folder dies with them
    if (b / "summary.json").exists():
        fail("run B finished before the kill: make the scene longer")
    pieces = sorted(p.name for p in b.glob("checkpoint-r*of*.pdcp"))
    if len(pieces) != n:
        fail(f"expected {n} checkpoint pieces after the kill, found {pieces}")
    restart = pd_run(pd, mpiexec, n, scene, b, ["--checkpoint-every", every, "--restart",
                                                str(b / "checkpoint.pdcp")])
    first = restart.splitlines()[0]
    print(first)
    step = int(first.rsplit(" ", 1)[1])
    if step >= 297 or step % int(every) != 0:
        fail(f"the restart should start from a checkpoint before the end: {first}")
    compare(a, b)
    for piece in pieces:
        if (a / piece).read_bytes() != (b / piece).read_bytes():
            fail(f"checkpoint piece {piece} differs")
    print(f"checkpoint pieces identical: {', '.join(pieces)}")


def errors(pd, mpiexec, scene, work, n):
    out = work / "o"
    printed = pd_run(pd, mpiexec, n, scene, out, ["--checkpoint-every", "300"])
    line = next((l for l in printed.splitlines() if "to continue: " in l), None)
    if line is None:
        fail(f"no restart command printed:\n{printed}")
    command = shlex.split(line.split("to continue: ", 1)[1])
    print(f"printed: {' '.join(command)}")
    if command[:3] != ["mpirun", "-np", str(n)] or command[3] != "pd":
        fail(f"the printed command does not run pd on {n} ranks: {line}")
    cmd = [*launcher(mpiexec, n), pd, *command[4:], "--threads", "1"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=120,
                       env=dict(os.environ, OMP_NUM_THREADS="1"))
    if p.returncode != 0:
        fail(f"the printed restart command failed (exit {p.returncode}):\n{p.stderr}")
    missing = out / f"checkpoint-r{n - 1:04d}of{n:04d}.pdcp"
    missing.unlink()
    cmd = [*launcher(mpiexec, n), pd, "run", scene, "-o", str(out), "--threads", "1",
           "--restart", str(out / "checkpoint.pdcp")]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        kill_all(proc.pid)
        proc.communicate()
        fail("a restart with a missing piece hangs (one rank waits for the one that failed)")
    # Every rank reads every piece (a set restarts on any rank count), so the rank that finds
    # the piece missing says so; a long path is shortened, so its words are checked, not the name.
    if proc.returncode != 1 or "cannot be opened" not in err:
        fail(f"a missing piece should end the job with exit 1 and the rank's message: exit "
             f"{proc.returncode}\n{err}")
    print("missing piece: exit 1 with the rank's message")


def set_recovery(pd, mpiexec, scene, work, n):
    import shutil
    every = ["--checkpoint-every", "300"]
    a = work / "a"
    pd_run(pd, mpiexec, n, scene, a, every)  # pieces of step 900
    short = work / "short.yaml"  # the same run, ended at step 600: pieces of step 600
    short.write_text(Path(scene).read_text().replace("end_time: 900", "end_time: 600"))
    b = work / "b"
    pd_run(pd, mpiexec, n, str(short), b, every)
    pieces = [f"checkpoint-r{r:04d}of{n:04d}.pdcp" for r in range(n)]
    for piece in pieces:
        if not (b / piece).exists() or not (a / piece).exists():
            fail(f"{piece} missing")

    def restart(folder, expect_step):
        out = pd_run(pd, mpiexec, n, scene, folder,
                     [*every, "--restart", str(folder / "checkpoint.pdcp")])
        first = out.splitlines()[0]
        print(f"{folder.name}: {first}")
        if int(first.rsplit(" ", 1)[1]) != expect_step:
            fail(f"{folder.name}: expected a restart at step {expect_step}: {first}")
        for piece in pieces:  # the set in place is the run's last, whole and alone
            if (folder / piece).read_bytes() != (a / piece).read_bytes():
                fail(f"{folder.name}: {piece} differs from the uninterrupted run's")
        left = [f.name for f in folder.iterdir() if f.name.endswith((".next", ".complete"))]
        if left:
            fail(f"{folder.name}: left behind {left}")

    # Killed while writing the step-900 set: rank 0's next piece written, no marker.
    writing = work / "writing"
    shutil.copytree(b, writing)
    shutil.copy(a / pieces[0], writing / (pieces[0] + ".next"))
    restart(writing, 600)
    # Killed while renaming the complete step-900 set: the marker stands, rank 0's piece is
    # renamed, the others' are still next pieces.
    renaming = work / "renaming"
    shutil.copytree(b, renaming)
    shutil.copy(a / pieces[0], renaming / pieces[0])
    for piece in pieces[1:]:
        shutil.copy(a / piece, renaming / (piece + ".next"))
    (renaming / "checkpoint.pdcp.complete").write_bytes(b"")
    restart(renaming, 900)


def stop(pd, mpiexec, scene, work, n):
    long_scene = work / "long.yaml"
    text = Path(scene).read_text()
    if "end_time: 900" not in text:
        fail("the stop test needs a scene ending at end_time: 900 (fracture-adr.yaml)")
    long_scene.write_text(text.replace("end_time: 900", "end_time: 1e7"))
    for sig, name in ((signal.SIGUSR1, "SIGUSR1"), (signal.SIGTERM, "SIGTERM")):
        out = work / name
        cmd = [*launcher(mpiexec, n), pd, "run", str(long_scene), "-o", str(out), "--threads",
               "1", "--checkpoint-every", "300"]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                start_new_session=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
        deadline = time.monotonic() + 120
        while not (out / "particles-00000300.pvtu").exists():  # every rank is stepping
            if proc.poll() is not None or time.monotonic() > deadline:
                kill_all(proc.pid)
                fail(f"{name}: the run ended or never started:\n{proc.communicate()[1]}")
            time.sleep(0.01)
        proc.send_signal(sig)  # to mpirun alone, as a scheduler or a user would
        try:
            _, err = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            kill_all(proc.pid)
            fail(f"{name} to mpirun: the job did not end within 60 s")
        print(f"{name} to mpirun: exit {proc.returncode}")
        if sig == signal.SIGUSR1 and proc.returncode != 5:
            fail(f"SIGUSR1 to mpirun should end the job with the run's exit 5:\n{err}")
        summary = out / "summary.json"
        if not summary.exists() or json.loads(summary.read_text())["status"] != "interrupted":
            fail(f"{name}: no interrupted summary.json (a rank did not stop cleanly):\n{err}")
        # The set is whole: the restart reads every piece and carries on from its step.
        steps = json.loads(summary.read_text())["steps"]
        more = work / f"{name}.yaml"
        more.write_text(text.replace("end_time: 900", f"end_time: {steps + 10}"))
        first = pd_run(pd, mpiexec, n, str(more), out, [
            "--checkpoint-every", "300", "--restart", str(out / "checkpoint.pdcp")
        ]).splitlines()[0]
        print(f"{name}: stopped at step {steps}; {first}")
        if int(first.rsplit(" ", 1)[1]) != steps:
            fail(f"{name}: the restart did not start from the interrupted step {steps}: {first}")

def rank_change(pd, mpiexec, scene, work, pairs):
    """A set written on N ranks restarts on M: each pair N:M runs the scene ended at step 600 on N
    ranks, restarts its set on M ranks to the end (900) and must equal an uninterrupted run."""
    every = ["--checkpoint-every", "300"]
    a = work / "uninterrupted"
    pd_run(pd, mpiexec, 1, scene, a, every)
    damage = compare_runs.arrays(a / "particles-00000600.vtu")["damage"]
    damaged = sum(1 for x in damage if float(x) > 0)
    if damaged == 0:
        fail("no bond breaks before the checkpoint at step 600: the test would not see them")
    short = work / "short.yaml"
    short.write_text(Path(scene).read_text().replace("end_time: 900", "end_time: 600"))
    for n, m in pairs:
        b = work / f"written-on-{n}-restarted-on-{m}"
        pd_run(pd, mpiexec, n, str(short), b, every)
        out = pd_run(pd, mpiexec, m, scene, b, [*every, "--restart", str(b / "checkpoint.pdcp")])
        first = out.splitlines()[0]
        print(f"{n} -> {m} ranks ({damaged} particles damaged at the checkpoint): {first}")
        if int(first.rsplit(" ", 1)[1]) != 600:
            fail(f"{n} -> {m}: expected a restart at step 600: {first}")
        compare(a, b)


def main():
    if len(sys.argv) != 7:
        fail(__doc__)
    mode, pd, mpiexec, scene, work, counts = sys.argv[1:]
    work = Path(work)
    subprocess.run(["rm", "-rf", str(work)], check=True)
    work.mkdir(parents=True)
    if mode == "ranks":
        ranks(pd, mpiexec, scene, work, [int(c) for c in counts.split(",")])
    elif mode == "errors":
        errors(pd, mpiexec, scene, work, int(counts))
    elif mode == "set-recovery":
        set_recovery(pd, mpiexec, scene, work, int(counts))
    elif mode == "stop":
        stop(pd, mpiexec, scene, work, int(counts))
    elif mode == "rank-change":
        rank_change(pd, mpiexec, scene, work,
                    [tuple(int(x) for x in p.split(":")) for p in counts.split(",")])
    elif mode == "kill-restart":
        kill_restart(pd, mpiexec, scene, work, int(counts))
    else:
        fail(f"unknown mode {mode}")
    print("PASS")


if __name__ == "__main__":
    main()
