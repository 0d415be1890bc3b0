"""What a report run would take on a quiet machine, from the CPU seconds its stages used.

A run on a loaded machine measures wall times that say more about the other processes than about
the report. The CPU time (user + system) of each stage's commands is nearly independent of the
load, so the driver records it beside the wall time, and this module replays the driver's schedule
with it:

* low:  every batch of side-by-side stages takes max(its CPU / cores, its longest stage's CPU),
        a stage that runs alone takes its CPU / cores (as if it used every core all the time);
* high: the side-by-side stages are list-scheduled on `jobs` workers in the order the driver
        submits them, each taking its CPU seconds (one thread each, as the driver runs them),
        and a stage that runs alone takes all its CPU seconds (as if it used one core).

Both are estimates: CPU time under load is itself a little inflated (shared caches), and neither
bound knows how well a lone stage's threads overlap. The page and report.json say so.
"""
from __future__ import annotations

import heapq


def schedule_batches(parallel: list[bool], jobs: int) -> list[list[int]]:
    """The driver's batches: consecutive parallel stages together, the others alone."""
    batches: list[list[int]] = []
    i = 0
    while i < len(parallel):
        batch = [i]
        if parallel[i] and jobs > 1:
            while i + len(batch) < len(parallel) and parallel[i + len(batch)]:
                batch.append(i + len(batch))
        batches.append(batch)
        i += len(batch)
    return batches


def list_schedule(durations: list[float], workers: int) -> float:
    """Makespan of running `durations` in this order on `workers` (each job to the first free)."""
    free = [0.0] * max(1, workers)
    heapq.heapify(free)
    end = 0.0
    for d in durations:
        start = heapq.heappop(free)
        heapq.heappush(free, start + d)
        end = max(end, start + d)
    return end


def quiet_estimate(stages: list[tuple[str, bool, float]], jobs: int, cores: int) -> dict:
    """stages: (name, parallel, cpu_seconds) in the driver's order, parallel batches in the
    order the driver submits them. Returns low and high estimates of the wall seconds."""
    low = high = 0.0
    for batch in schedule_batches([p for _, p, _ in stages], jobs):
        cpu = [stages[k][2] for k in batch]
        if len(batch) > 1:
            low += max(sum(cpu) / cores, max(cpu))
            high += list_schedule(cpu, jobs)
        else:
            low += cpu[0] / cores
            high += cpu[0]
    return {"low_seconds": low, "high_seconds": high, "cores": cores, "jobs": jobs,
            "cpu_seconds": sum(c for _, _, c in stages),
            "meaning": "wall time this run's stages would take on a quiet machine with these "
                       "cores, estimated from their CPU seconds (reports/pdreport/timing.py)"}
