"""Render the stage records into DIR/index.html + PNG figures + DIR/report.json.

Everything shown comes from the stage records (real runs).  A stage that failed is shown as a red
box with its error; nothing is filled in for it.  The metrics of report.json are computed from the
records first (metrics.py); the page only shows them.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

from . import cases as case_files
from . import (casedetails, distributed, fibres, fracture, griffith, integrators, performance, scenes,
               scorecard, structures, summary)
from .fmt import esc
from .markup import CHECK_SCRIPT, CSS, num_td, table
from .metrics import metrics
from .page import Page

SECTIONS = (("scorecard", "Scorecard"), ("environment", "Environment"), ("summary", "Summary"),
            ("convergence", "Convergence"), ("deflections", "Deflections"),
            ("accuracy", "Accuracy vs time"), ("scenes", "Your scenes"), ("integrators", "Integrators"),
            ("performance", "Performance"), ("mpi", "MPI"), ("fibres", "Virtual fibres"), ("griffith", "Griffith"), ("fracture", "Fracture"), ("cases", "Cases"), ("stages", "Stages"))


def page_html(page: Page) -> str:
    # The scorecard comes first: it is the page's answer, everything below is its evidence.
    parts = [scorecard.section(page), header(page), summary.section(page), structures.deflections(page),
             structures.accuracy_vs_time(page), scenes.section(page), integrators.section(page),
             performance.section(page), distributed.section(page), fibres.section(page), griffith.section(page),
             fracture.section(page), casedetails.section(page), stage_table(page)]
    body = "\n".join(parts)
    nav = " ".join(f'<a href="#{i}">{t}</a>' for i, t in SECTIONS)
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>libpd verification report</title><style>{CSS}</style></head>"
            f"<body data-check=\"pending\"><h1>libpd verification report</h1><nav>{nav}</nav>\n"
            f"{body}\n{CHECK_SCRIPT}</body></html>\n")


def header(page: Page) -> str:
    e = page.env
    rows = [["libpd", esc(e.get("libpd"))], ["git commit", esc(e.get("git_commit"))],
            ["deal.II (Debian)", esc(e.get("deal.II"))], ["SUNDIALS (Debian)", esc(e.get("SUNDIALS"))],
            ["LAMMPS (Debian)", esc(e.get("LAMMPS"))],
            ["compiler", esc(e.get("compiler"))], ["build", f"{esc(e.get('build_dir'))} ({esc(e.get('build_type', '?'))})"],
            ["CPU", f"{esc(e.get('cpu'))}, {esc(e.get('cores'))} cores"],
            ["threads", f"{esc(e.get('threads'))} (OpenMP default; benchmarks set their own)"],
            ["load average at start", esc(e.get("loadavg_at_start"))],
            ["date", esc(e.get("date"))], ["mode", esc(page.meta.get("mode"))],
            ["python / matplotlib", f"{esc(e.get('python'))} / {esc(e.get('matplotlib'))}"]]
    n_failed = sum(1 for r in page.rec.values() if r.get("status") != "ok")
    total = page.meta.get("total_seconds")
    q = page.meta.get("quiet_estimate") or {}
    quiet = (f"; {q['cpu_seconds']:.0f} CPU s, on a quiet {q['cores']}-core machine an estimated "
             f"{q['low_seconds']:.0f}–{q['high_seconds']:.0f} s (from the stages' CPU seconds, "
             f"see Stages and timings)" if q.get("cpu_seconds") else "")
    status = (f'<p class="{"fail" if n_failed else "pass"}">{len(page.rec)} stages, '
              f'{n_failed} failed' + (f", {total:.0f} s wall for this run" if total else "") +
              quiet + ".</p>")
    return ('<section id="environment"><h2>Environment</h2>' + status +
            table(["", ""], rows, 'id="environment-table"') + "</section>")


def stage_table(page: Page) -> str:
    rows = []
    total_fresh = sum(r.get("seconds", 0) for r in page.rec.values() if not r.get("cached"))
    total_all = sum(r.get("seconds", 0) for r in page.rec.values())
    groups: dict[str, float] = {}
    for r in page.rec.values():
        groups[r.get("group", "?")] = groups.get(r.get("group", "?"), 0) + r.get("seconds", 0)
    for name, r in page.rec.items():
        st = r.get("status")
        cls = "pass" if st == "ok" else "fail"
        rows.append([f"<code>{esc(name)}</code>", f'<span class="{cls}">{esc(st)}</span>',
                     num_td(f"{r.get('seconds', 0):.1f}"),
                     num_td("" if r.get("cpu_seconds") is None else f"{r['cpu_seconds']:.1f}"),
                     num_td(esc(r.get("threads", ""))), "cached" if r.get("cached") else "ran",
                     "<br>".join(f"<code>{esc(' '.join(c))}</code>" for c in r.get("commands", [])),
                     esc((r.get("error") or "")[:300])])
    dom = ""
    if groups and total_all > 0:
        top = sorted(groups.items(), key=lambda kv: -kv[1])
        dom = ("<p class=\"reading\">Time (as recorded when each stage last ran): " +
               ", ".join(f"{g} {s:.0f} s ({100 * s / total_all:.0f} %)" for g, s in top[:5]) +
               f". <b>{esc(top[0][0])}</b> dominates. This run computed {total_fresh:.0f} s; "
               f"the rest came from the cache. CPU s is user + system time of the stage's "
               f"commands (their CPU cost whatever else loaded the machine); threads is the "
               f"OMP_NUM_THREADS it ran with.</p>")
    return ('<section id="stages"><h2>Stages and timings</h2>' + dom +
            table(["stage", "status", "wall s", "CPU s", "threads", "this run", "command", "error"], rows,
                  'id="stage-table"') + "</section>")


def render(out: Path, records: dict[str, dict], env: dict, meta: dict) -> dict:
    cases = case_files.load()
    measured = metrics(records, meta, cases)
    out.mkdir(parents=True, exist_ok=True)
    for f in out.glob("*.png"):
        f.unlink()
    page = Page(out, records, env, meta, cases)
    text = page_html(page)
    tmp = out / "index.html.tmp"
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, out / "index.html")
    report = {
        "schema": "libpd-report/1",
        "environment": env,
        "meta": meta,
        "stages": {k: {kk: v.get(kk) for kk in ("group", "status", "seconds", "cpu_seconds", "threads",
                                                     "loadavg_at_start", "cached", "error", "commands")}
                   for k, v in records.items()},
        "figures": page.figures,
        "metrics": measured,
        "data": {k: v.get("result") for k, v in records.items()},
    }
    tmp = out / "report.json.tmp"
    tmp.write_text(json.dumps(report, indent=1, default=str), encoding="utf-8")
    os.replace(tmp, out / "report.json")
    return report
