"""Render the stage records into DIR/index.html + PNG figures + DIR/report.json.

Everything shown comes from the stage records (real runs).  A stage that failed is shown as a red
box with its error; nothing is filled in for it.
"""
from __future__ import annotations

import html
import json
import math
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from . import theory as th  # noqa: E402

# Miranda et al. 2019: agreement of their PD with their FE model.
PAPER_LEVEL = {"clamped-beam": 0.03, "cantilever": 0.01, "plate-3clamped": 0.04}
STRUCTURES = ["clamped-beam", "cantilever", "plate-3clamped"]
FE_LINE_FILES = {
    ("clamped-beam", "centreline"): "clamped-beam-centreline.csv",
    ("cantilever", "centreline"): "cantilever-centreline.csv",
    ("plate-3clamped", "perpendicular"): "plate-3clamped-perpendicular.csv",
    ("plate-3clamped", "free_edge"): "plate-3clamped-free_edge.csv",
}
# Miranda Figs. 8, 10, 14, 15
PAPER_FIG = {("clamped-beam", "centreline"): "Fig. 8", ("cantilever", "centreline"): "Fig. 10",
             ("plate-3clamped", "perpendicular"): "Fig. 14",
             ("plate-3clamped", "free_edge"): "Fig. 15"}
LINE_AXIS = {("clamped-beam", "centreline"): "x", ("cantilever", "centreline"): "x",
             ("plate-3clamped", "perpendicular"): "y", ("plate-3clamped", "free_edge"): "x"}

CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;margin:0 auto;
 max-width:1250px;padding:0 18px 40px;color:#1d1d1f;line-height:1.4}
h1{margin:18px 0 4px} h2{border-bottom:2px solid #ccd;padding-bottom:3px;margin-top:34px}
h3{margin:18px 0 6px}
table{border-collapse:collapse;margin:8px 0 14px;font-size:13px}
th,td{border:1px solid #ccd;padding:3px 7px;vertical-align:top;text-align:left}
th{background:#eef0f6} td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
.pass{color:#0a7a28;font-weight:600} .fail{color:#b3141a;font-weight:600}
.failed{border:2px solid #b3141a;background:#fff1f1;padding:8px 12px;margin:10px 0;border-radius:4px}
.failed pre{white-space:pre-wrap;font-size:12px;margin:6px 0 0;max-height:220px;overflow:auto}
.note{color:#555;font-size:13px} .reading{background:#f3f7ee;border-left:4px solid #6a9a3a;
 padding:6px 10px;margin:6px 0}
img{max-width:100%;border:1px solid #dde} .figs{display:flex;flex-wrap:wrap;gap:10px}
.figs figure{margin:0;flex:1 1 560px} figcaption{font-size:12px;color:#444}
code{background:#f2f2f6;padding:0 3px;border-radius:3px;font-size:12px}
nav a{margin-right:12px} .tw{overflow-x:auto;max-width:100%}
"""

CHECK_SCRIPT = """
<script>
// Browser self-check (used by tests/report): every image loaded?
function pdCheckImages(){
  var imgs=document.images, loaded=0, broken=[];
  for(var i=0;i<imgs.length;i++){
    var im=imgs[i];
    if(im.complete && im.naturalWidth>0){loaded++;} else {broken.push(im.getAttribute('src'));}
  }
  var b=document.body;
  b.setAttribute('data-images-total', String(imgs.length));
  b.setAttribute('data-images-loaded', String(loaded));
  b.setAttribute('data-images-broken', broken.join(' '));
  b.setAttribute('data-summary-rows',
    String(document.querySelectorAll('#summary-table tbody tr[data-case]').length));
  b.setAttribute('data-check', broken.length===0 ? 'images-ok' : 'images-broken');
}
window.addEventListener('load', pdCheckImages);
</script>
"""


def esc(x: object) -> str:
    return html.escape(str(x))


def fnum(v: object, digits: int = 4) -> str:
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, (int,)) and not isinstance(v, bool):
        return f"{v:,}".replace(",", " ")
    try:
        f = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return esc(v)
    if not math.isfinite(f):
        return str(f)
    if f == 0:
        return "0"
    if abs(f) >= 1e5 or abs(f) < 1e-3:
        return f"{f:.{digits}g}" if 1e-3 <= abs(f) < 1e5 else f"{f:.{digits - 1}e}"
    return f"{f:.{digits}g}"


def pct(v: object, digits: int = 3) -> str:
    try:
        f = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return "–"
    return f"{100 * f:.{digits}g} %"


def table(headers: list[str], rows: list[list[str]], attrs: str = "",
          row_attrs: list[str] | None = None) -> str:
    out = [f'<div class="tw"><table {attrs}><thead><tr>' + "".join(f"<th>{h}</th>" for h in headers) +
           "</tr></thead><tbody>"]
    for i, r in enumerate(rows):
        ra = (" " + row_attrs[i]) if row_attrs and row_attrs[i] else ""
        out.append(f"<tr{ra}>" + "".join(
            c if c.startswith("<td") else f"<td>{c}</td>" for c in r) + "</tr>")
    out.append("</tbody></table></div>")
    return "".join(out)


def num_td(s: str, cls: str = "num") -> str:
    return f'<td class="{cls}">{s}</td>'


def failed_box(rec: dict | None, what: str) -> str:
    if rec is None:
        return (f'<div class="failed" data-failed="{esc(what)}"><b>NOT RUN</b> — {esc(what)}: '
                "the stage was not part of this run.</div>")
    cmds = "<br>".join(f"<code>{esc(' '.join(c))}</code>" for c in rec.get("commands", []))
    return (f'<div class="failed" data-failed="{esc(rec["name"])}"><b>FAILED</b> — stage '
            f'<code>{esc(rec["name"])}</code> ({esc(what)}) after {rec.get("seconds", 0):.1f} s. '
            f"Command: {cmds}<pre>{esc(rec.get('error') or 'no error message')}</pre></div>")


def ok(rec: dict | None) -> bool:
    return bool(rec) and rec.get("status") == "ok" and rec.get("result") is not None


class Page:
    def __init__(self, out: Path, records: dict[str, dict], env: dict, meta: dict):
        self.out = out
        self.rec = records
        self.env = env
        self.meta = meta
        self.metrics: dict[str, dict] = {}
        self.figures: list[str] = []

    # -- metrics for --compare
    def metric(self, name: str, value: object, kind: str, **extra: object) -> None:
        if value is None:
            return
        if isinstance(value, float) and not math.isfinite(value):
            return
        self.metrics[name] = {"value": value, "kind": kind, **extra}

    def group(self, g: str) -> dict[str, dict]:
        return {k: v for k, v in self.rec.items() if v.get("group") == g}

    def savefig(self, fig, name: str) -> str:
        path = self.out / name
        fig.savefig(path, dpi=110, bbox_inches="tight")
        plt.close(fig)
        self.figures.append(name)
        return name

    # ---------------------------------------------------------------------------------------
    def render(self) -> str:
        parts = [self.header(), self.summary(), self.deflections(), self.accuracy_vs_time(),
                 self.integrators(), self.performance(), self.stage_table()]
        for name, rec in self.rec.items():
            self.metric(f"stage.{name}.ok", rec.get("status") == "ok", "gate")
            if rec.get("status") == "ok" and not rec.get("cached"):
                self.metric(f"stage.{name}.seconds", rec.get("seconds"), "time", abs_tol=5.0)
        body = "\n".join(parts)
        nav = " ".join(f'<a href="#{i}">{t}</a>' for i, t in (
            ("summary", "Summary"), ("deflections", "Deflections"), ("accuracy", "Accuracy vs time"),
            ("integrators", "Integrators"), ("performance", "Performance"), ("stages", "Stages")))
        return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>libpd verification report</title><style>{CSS}</style></head>"
                f"<body data-check=\"pending\"><h1>libpd verification report</h1><nav>{nav}</nav>\n"
                f"{body}\n{CHECK_SCRIPT}</body></html>\n")

    # ---------------------------------------------------------------------------------------
    def header(self) -> str:
        e = self.env
        rows = [["libpd", esc(e.get("libpd"))], ["git commit", esc(e.get("git_commit"))],
                ["deal.II (Debian)", esc(e.get("deal.II"))], ["SUNDIALS (Debian)", esc(e.get("SUNDIALS"))],
                ["LAMMPS (Debian)", esc(e.get("LAMMPS"))],
                ["compiler", esc(e.get("compiler"))], ["build", f"{esc(e.get('build_dir'))} ({esc(e.get('build_type', '?'))})"],
                ["CPU", f"{esc(e.get('cpu'))}, {esc(e.get('cores'))} cores"],
                ["threads", f"{esc(e.get('threads'))} (OpenMP default; benchmarks set their own)"],
                ["load average at start", esc(e.get("loadavg_at_start"))],
                ["date", esc(e.get("date"))], ["mode", esc(self.meta.get("mode"))],
                ["python / matplotlib", f"{esc(e.get('python'))} / {esc(e.get('matplotlib'))}"]]
        n_failed = sum(1 for r in self.rec.values() if r.get("status") != "ok")
        total = self.meta.get("total_seconds")
        status = (f'<p class="{"fail" if n_failed else "pass"}">{len(self.rec)} stages, '
                  f'{n_failed} failed' + (f", {total:.0f} s wall for this run" if total else "") +
                  ".</p>")
        return ('<section id="environment"><h2>Environment</h2>' + status +
                table(["", ""], rows, 'id="environment-table"') + "</section>")

    # ---------------------------------------------------------------------------------------
    def summary(self) -> str:
        verify = self.group("verify")
        fem = {r["result"]["problem"]: r["result"] for r in self.group("fem").values() if r.get("result")}
        rows, attrs = [], []
        listed = [c for c, _ in self.meta.get("cases", [])] or [n.split(":", 1)[1] for n in verify]
        for case in listed:
            rec = verify.get(f"verify:{case}")
            attrs.append(f'data-case="{esc(case)}"')
            if rec is None and case.endswith("-sweep"):
                rows.append(self.sweep_summary_row(case))
                continue
            if rec is None:
                summ = dict((c, t) for c, t in self.meta.get("cases", [])).get(case, "")
                why = ("not run in the default report: <code>pd verify --list</code> marks it slow; "
                       "<code>--full</code> runs it") if "(slow)" in summ else "not run"
                rows.append([f"<b>{esc(case)}</b>", f"<i>{why}</i><br><small>{esc(summ)}</small>"] + ["–"] * 11)
                continue
            if not ok(rec):
                err = esc((rec.get("error") or "")[:400])
                rows.append([f"<b>{esc(case)}</b>", f'<span class="fail">stage FAILED</span><br><small>{err}</small>']
                            + ["–"] * 11)
                self.metric(f"verify.{case}.passed", False, "gate")
                continue
            rows.append(self.summary_row(case, rec["result"], fem))
        head = ["case", "quantity", "PD", "FE (deal.II)", "analytical", "error vs FE",
                "error vs analytical", "Miranda's PD–FE agreement", "gate", "passed",
                "wall (s)", "particles", "bonds"]
        if not verify:
            return ('<section id="summary"><h2>Summary</h2>' +
                    failed_box(None, "pd verify (no verification stage ran)") +
                    table(head, [], 'id="summary-table"') + "</section>")
        note = ("<p class=\"note\">Errors are relative. FE = finest-mesh-extrapolated deal.II Q2 value "
                "(fem_reference/reference); analytical = Timoshenko (Euler–Bernoulli in brackets) for "
                "the beams, Kirchhoff for the plate, the modal series / σ/E for the bar and the block. "
                "Miranda's column is the agreement the paper reports between its PD and FE models "
                "(clamped beam 3 %, cantilever 1 %, plate 4 %); ours is in <i>error vs FE</i>. "
                "For the structures, <i>budget</i> splits PD/FE into the factor the cross-section's "
                "own stiffness predicts and what the supports, load and ends add "
                "(verification/cases/STRUCTURES.md).</p>")
        fails = [n for n, r in verify.items() if ok(r) and not r["result"].get("passed")]
        failtxt = (f"<p class=\"fail\">Gates failing: {esc(', '.join(f.split(':')[1] for f in fails))}</p>"
                   if fails else "<p class=\"pass\">All gates that ran passed.</p>")
        return ('<section id="summary"><h2>Summary</h2>' + failtxt + note +
                table(head, rows, 'id="summary-table"', attrs) + "</section>")

    def sweep_summary_row(self, case: str) -> list[str]:
        base = case.removesuffix("-sweep")
        rec = self.rec.get(f"sweep:{base}")
        head = [f"<b>{esc(case)}</b>"]
        if rec is None:
            return head + ['accuracy-vs-time sweep: <i>not run in this mode</i> (<code>--full</code> runs it)'] + ["–"] * 11
        if not ok(rec):
            return head + ['<span class="fail">sweep stage FAILED</span> (see Accuracy vs time)'] + ["–"] * 11
        res = rec["result"]
        pts = [(sweep_error(r), r) for r in res["rows"] if sweep_error(r) is not None]
        best = min(pts, key=lambda p: p[0]) if pts else None
        txt = f'<a href="#accuracy">accuracy-vs-time sweep</a>: {len(res["rows"])} runs' + (
            " (reduced)" if res.get("reduced") else "")
        if best:
            txt += f'; best {esc(best[1].get("knob"))} = {esc(short(best[1].get("knob_value")))}'
        return head + [txt, "–", "–", "–", num_td(pct(best[0]) if best else "–"), "–", "–",
                       "none: a measurement", "–", num_td(fnum(rec.get("seconds"), 3)), "–", "–"]

    def summary_row(self, case: str, d: dict, fem: dict) -> list[str]:
        base = case.removesuffix("-fast")
        pdv, ref, err, gate = d.get("pd", {}), d.get("reference", {}), d.get("error", {}), d.get("gate", {})
        for k, v in flatten(err).items():
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                self.metric(f"verify.{case}.error.{k}", v, "error")
        for k, v in flatten(pdv).items():
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                self.metric(f"verify.{case}.pd.{k}", v, "count" if isinstance(v, int) else "value")
        self.metric(f"verify.{case}.passed", bool(d.get("passed")), "gate")
        self.metric(f"verify.{case}.wall_seconds", d.get("wall_seconds"), "time", abs_tol=1.0)
        particles = d.get("particles", (d.get("run") or {}).get("particles"))
        bonds = d.get("bonds", (d.get("run") or {}).get("bonds"))
        self.metric(f"verify.{case}.particles", particles, "count")
        self.metric(f"verify.{case}.bonds", bonds, "count")
        passed = d.get("passed")
        pcell = f'<span class="{"pass" if passed else "fail"}">{"PASS" if passed else "FAIL"}</span>'
        if isinstance(gate, dict):
            gtxt = "<br>".join(f"{esc(k)} ≤ {pct(v)}" if isinstance(v, (int, float)) else f"{esc(k)}: {esc(v)}"
                               for k, v in gate.items())
        else:
            gtxt = esc(gate)
        quantity = esc(d.get("quantity", ""))
        wall = num_td(fnum(d.get("wall_seconds"), 3))
        if base in STRUCTURES and isinstance(ref, dict):
            pd_l, fe_l, an_l, efe_l, ean_l = [], [], [], [], []
            for q, v in pdv.items():
                r = ref.get(q, {})
                pd_l.append(f"{esc(q)}: {fnum(v)}")
                fe_l.append(fnum(r.get("fe")))
                if "timoshenko" in r:
                    an_l.append(f"T {fnum(r['timoshenko'])} (EB {fnum(r.get('euler_bernoulli'))})")
                    ean_l.append(f"T {pct(err.get(q + '_vs_timoshenko'))} (EB {pct(err.get(q + '_vs_euler_bernoulli'))})")
                elif "kirchhoff" in r:
                    an_l.append(f"K {fnum(r['kirchhoff'])}")
                    ean_l.append(f"K {pct(err.get(q + '_vs_kirchhoff'))}")
                else:
                    an_l.append("–")
                    ean_l.append("–")
                efe_l.append(pct(err.get(q + "_vs_fe")))
            for k, v in err.items():
                if k.startswith("line_"):
                    efe_l.append(f"<small>{esc(k.removeprefix('line_').replace('_max_over_max_fe', ''))} line max: {pct(v)}</small>")
            budget = d.get("error_budget", {})
            first = next((b for b in budget.values() if isinstance(b, dict)), None)
            if first:
                sec = d.get("section_stiffness", {})
                efe_l.append(f"<small>budget: section ×{fnum(first.get('section_factor'), 4)} "
                             f"(bending {fnum(sec.get('bending'), 3)}, shear {fnum(sec.get('shear'), 3)}), "
                             f"supports/load/ends ×{fnum(first.get('remaining_factor'), 4)}</small>")
            paper = pct(PAPER_LEVEL.get(base))
            return [f"<b>{esc(case)}</b>", quantity, num_td("<br>".join(pd_l)), num_td("<br>".join(fe_l)),
                    num_td("<br>".join(an_l)), num_td("<br>".join(efe_l)), num_td("<br>".join(ean_l)),
                    num_td(paper), gtxt, pcell, wall, num_td(fnum(particles)), num_td(fnum(bonds))]
        # generic case
        pd_txt = "<br>".join(f"{esc(k)}: {fnum(v)}" for k, v in flatten(pdv).items()) if isinstance(pdv, dict) else fnum(pdv)
        ref_txt = "<br>".join(f"{esc(k)}: {fnum(v)}" for k, v in flatten(ref).items()) if isinstance(ref, dict) else fnum(ref)
        err_txt = "<br>".join(f"{esc(k)}: {pct(v)}" for k, v in flatten(err).items()) if isinstance(err, dict) else pct(err)
        return [f"<b>{esc(case)}</b>", quantity, num_td(pd_txt), "–", num_td(ref_txt), "–", num_td(err_txt),
                "–", gtxt, pcell, wall, num_td(fnum(particles)), num_td(fnum(bonds))]

    # ---------------------------------------------------------------------------------------
    def deflections(self) -> str:
        parts = ['<section id="deflections"><h2>Deflection lines: PD vs deal.II vs theory</h2>',
                 '<p class="note">As Miranda et al. 2019 Figs. 8, 10, 14, 15. PD values on the '
                 "particle layers of the centre line (interpolated to the line through the body's "
                 "centre), FE = deal.II Q2 finest mesh, theory = Euler–Bernoulli and Timoshenko "
                 "closed forms (beams; parameters from the gold file's <code>theory</code>) and the "
                 "Kirchhoff Rayleigh–Ritz point values (plate). Lower panels: (PD − FE) / max|FE| "
                 "along the line.</p>"]
        fem = {r["result"]["problem"]: r["result"] for r in self.group("fem").values() if r.get("result")}
        for r in self.group("fem").values():
            if not ok(r):
                parts.append(failed_box(r, "FE reference check"))
        figs = []
        for case in STRUCTURES:
            rec = self.rec.get(f"verify:{case}")
            if not ok(rec):
                parts.append(failed_box(rec, f"verification case {case} (deflection lines)"))
                continue
            d = rec["result"]
            for line, ldata in (d.get("lines") or {}).items():
                figs.append(self.deflection_figure(case, line, ldata, d, fem.get(case)))
        parts.append('<div class="figs">' + "".join(figs) + "</div></section>")
        return "".join(parts)

    def deflection_figure(self, case: str, line: str, ldata: dict, d: dict, fem: dict | None) -> str:
        cols = ldata.get("columns", ["position", "pd", "fe"])
        rows = ldata.get("rows", [])
        ip, ipd, ife = cols.index("position"), cols.index("pd"), cols.index("fe")
        x = [r[ip] for r in rows]
        pdv = [r[ipd] * 1e3 for r in rows]
        fev = [r[ife] * 1e3 for r in rows]
        fig, (ax, ax2) = plt.subplots(2, 1, figsize=(6.4, 5.2), sharex=True,
                                      gridspec_kw={"height_ratios": [3, 1.3]})
        axis = LINE_AXIS.get((case, line), "s")
        fe_src = "FE at PD layers"
        if fem and FE_LINE_FILES.get((case, line)) in fem.get("lines", {}):
            fl = fem["lines"][FE_LINE_FILES[(case, line)]]
            ax.plot(fl[axis], [v * 1e3 for v in fl["deflection"]], "-", color="#1f5fbf", lw=2,
                    label="deal.II (Q2, finest mesh)")
            fe_src = "deal.II line"
        else:
            ax.plot(x, fev, "-", color="#1f5fbf", lw=2, label="deal.II (at PD layers)")
        theory_obj = (fem or {}).get("theory") or {}
        note = ""
        if th.beam_kind(theory_obj):
            length = float(theory_obj["L"])
            xs = [length * i / 200 for i in range(201)]
            eb = [th.beam_deflection(theory_obj, xx)[0] * 1e3 for xx in xs]
            ti = [th.beam_deflection(theory_obj, xx)[1] * 1e3 for xx in xs]
            ax.plot(xs, eb, ":", color="#777", lw=1.5, label="Euler–Bernoulli")
            ax.plot(xs, ti, "--", color="#2a8a2a", lw=1.5, label="Timoshenko (κ = 5/6)")
            note = f" Closed forms reproduce the gold file's point values to {th.check_against_gold(theory_obj):.1e}."
        elif theory_obj.get("quantities"):
            pts = {"centre": (2.0, 1.5), "free_edge_mid": (2.0, 3.0)}
            for qname, q in theory_obj["quantities"].items():
                if qname not in pts or not isinstance(q, dict) or "kirchhoff" not in q:
                    continue
                px, py = pts[qname]
                if line == "perpendicular":
                    pos = py
                elif line == "free_edge" and abs(py - 3.0) < 1e-9:
                    pos = px
                else:
                    continue
                ax.plot([pos], [q["kirchhoff"] * 1e3], "*", ms=13, color="#2a8a2a",
                        label=f"Kirchhoff {qname.replace('_', ' ')}")
        elif fem is None:
            note = " (FE reference stage missing: no theory curve.)"
        ax.plot(x, pdv, "o", ms=3.5, color="#c0392b", label="PD (libpd)")
        ax.invert_yaxis()
        ax.set_ylabel("deflection (mm, downward)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        s = d.get("settings", {})
        ax.set_title(f"{case} — {line} ({PAPER_FIG.get((case, line), '')}); "
                     f"λ = {s.get('spacing', '?')} m, {s.get('stretch', '?')}", fontsize=10)
        fmax = max((abs(v) for v in fev), default=1.0) or 1.0
        ax2.plot(x, [100 * (p - f) / fmax for p, f in zip(pdv, fev)], "-o", ms=2.5, color="#c0392b")
        ax2.axhline(0, color="k", lw=0.6)
        ax2.set_ylabel("(PD−FE)/max|FE| (%)", fontsize=8)
        ax2.set_xlabel(f"{axis} (m)")
        ax2.grid(alpha=0.3)
        name = self.savefig(fig, f"deflection-{case}-{line}.png")
        err = ldata.get("max_difference_over_max_fe")
        self.metric(f"line.{case}.{line}.max_difference_over_max_fe", err, "error")
        return (f'<figure><img src="{name}" alt="{esc(case)} {esc(line)} deflection"><figcaption>'
                f"{esc(case)}, {esc(line)}: largest |PD − FE| / max|FE| = {pct(err)} "
                f"({len(rows)} PD layers; FE curve: {fe_src}).{esc(note)}</figcaption></figure>")

    # ---------------------------------------------------------------------------------------
    def accuracy_vs_time(self) -> str:
        parts = ['<section id="accuracy"><h2>Accuracy vs time</h2>',
                 '<p class="note">Each point is one run of <code>pd verify --sweep CASE</code>: the '
                 "error against deal.II (largest over the case's quantities) against the wall time of "
                 "the run, one marker series per knob. The Pareto front (no other run is both "
                 "faster and more accurate) is the black line.</p>"]
        sweeps = self.group("sweep")
        if not sweeps:
            parts.append(failed_box(None, "accuracy-vs-time sweeps"))
        for name, rec in sweeps.items():
            case = name.split(":", 1)[1]
            parts.append(f"<h3>{esc(case)}</h3>")
            if not ok(rec):
                parts.append(failed_box(rec, f"sweep of {case}"))
                continue
            parts.append(self.sweep_block(case, rec["result"]["rows"], rec["result"]))
        parts.append("</section>")
        return "".join(parts)

    def sweep_block(self, case: str, rows: list[dict], result: dict | None = None) -> str:
        pts = []
        for r in rows:
            e = sweep_error(r)
            t = r.get("wall_seconds")
            if e is None or not t or t <= 0:
                continue
            pts.append((float(t), abs(e), str(r.get("knob", "?")), r.get("knob_value"), r))
        if not pts:
            return '<p class="fail">the sweep rows have no usable error_vs_fe / wall_seconds</p>'
        base = next((p for p in pts if p[2] == "baseline"), None)
        fig, ax = plt.subplots(figsize=(7.4, 4.8))
        markers = "osD^v<>pP*X"
        knobs = sorted({p[2] for p in pts if p[2] != "baseline"})
        for i, k in enumerate(knobs):
            sel = [p for p in pts if p[2] == k]
            if base is not None:
                sel = sel + [base]
            sel.sort(key=lambda p: p[0])
            line, = ax.loglog([p[0] for p in sel], [max(p[1], 1e-12) for p in sel],
                              markers[i % len(markers)], ls="-", lw=0.7, ms=6, alpha=0.85, label=k)
            for p in sel:
                if p is base:
                    continue
                ax.annotate(short(p[3]), (p[0], max(p[1], 1e-12)), fontsize=6.5, xytext=(3, 3),
                            textcoords="offset points", color=line.get_color())
        if base is not None:
            ax.loglog([base[0]], [max(base[1], 1e-12)], "*", ms=16, color="k", mfc="gold",
                      label="baseline (the scene)", zorder=5)
        front = pareto(pts)
        ax.loglog([p[0] for p in front], [max(p[1], 1e-12) for p in front], "-", color="k", lw=2.2,
                  alpha=0.35, label="Pareto front", zorder=0)
        ax.set_xlabel("wall time of the run (s)")
        ax.set_ylabel("relative error vs FE (largest quantity)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
        ax.set_title(f"{case}: error vs wall time", fontsize=10)
        img = self.savefig(fig, f"accuracy-{case}.png")
        for p in pts:
            key = f"sweep.{case}.{p[2]}={short(p[3])}"
            self.metric(key + ".error", p[1], "error")
            self.metric(key + ".wall_seconds", p[0], "time", abs_tol=1.0)
        readings = sweep_readings(pts)
        extra = ""
        if result and result.get("observed_order_in_spacing") is not None:
            extra = (f'<p class="note">Observed order in λ (least squares of log error vs log λ over the '
                     f'spacing runs): {fnum(result["observed_order_in_spacing"], 3)}.</p>')
        if result and result.get("reduced"):
            extra += ('<p class="note">Default report: a <b>reduced sweep</b> (the first value of each '
                      "knob list of the case file, besides the baseline); <code>--full</code> runs the "
                      "complete sweeps of all three structures.</p>")
        trows = [[esc(p[2]), esc(short(p[3])), num_td(pct(p[1])), num_td(fnum(p[0], 3)),
                  num_td(fnum(p[4].get("spacing"))), num_td(fnum(p[4].get("horizon_factor"), 3)),
                  esc(p[4].get("stretch", "")), esc(f"{p[4].get('surface_correction', '')}/{p[4].get('volume_correction', '')}"),
                  num_td(fnum(p[4].get("force_tolerance"))),
                  num_td(fnum(p[4].get("particles"))), num_td(fnum(p[4].get("bonds"))),
                  num_td(fnum(p[4].get("bond_updates"))), esc(p[4].get("status", "")),
                  "★" if p in front else ""]
                 for p in sorted(pts, key=lambda p: (p[2] != "baseline", p[2], p[0]))]
        return (f'<img src="{img}" alt="accuracy vs time {esc(case)}">' +
                "".join(f'<p class="reading">{esc(r)}</p>' for r in readings) + extra +
                table(["knob", "value", "error vs FE", "wall (s)", "λ (m)", "δ/λ", "stretch",
                       "corrections (surface/volume)", "force tol.", "particles", "bonds",
                       "bond updates", "status", "Pareto"], trows, 'class="sweep-table"'))

    # ---------------------------------------------------------------------------------------
    def integrators(self) -> str:
        parts = ['<section id="integrators"><h2>Integrators</h2>', "<h3>Stability limit</h3>",
                 '<p class="note"><code>pd stability SCENE --json</code>: the largest fixed Δt that '
                 "stays bounded, found by bisection, beside Miranda's eq. 31 bound and two sharp "
                 "predictions: β/ω<sub>max</sub> (β = the method's stability interval on the imaginary "
                 "axis, 2 for Verlet; ω<sub>max</sub> by Lanczos on the linearised operator), the "
                 "limit of infinitely long runs, and the finite-horizon prediction of the bounded "
                 "run itself: the perturbation's energy, split over the modes by a Lanczos (Gauss "
                 "quadrature) spectral measure, grows by |R(iωΔt)|<sup>2N</sup> per mode in N steps, "
                 "and the run counts as unstable once it has grown 1000-fold. Tables whose |R(iy)| "
                 "exceeds 1 only marginally (Dormand–Prince past β, and Heun–Euler, Cash–Karp, "
                 "Fehlberg with β = 0) have a finite measured limit that only the second prediction "
                 "describes; it tends to β/ω<sub>max</sub> as N grows.</p>"]
        rec = self.rec.get("stability")
        if not ok(rec):
            parts.append(failed_box(rec, "stability limits"))
        else:
            rows = []
            for r in rec["result"]["rows"]:
                rows.append([esc(r.get("case")), esc(r.get("integrator")), num_td(fnum(r.get("interval"))),
                             num_td(fnum(r.get("measured_dt"))), num_td(fnum(r.get("eq31_dt"))),
                             num_td(fnum(r.get("sharp_dt")) if r.get("sharp_dt") else "– (β = 0)"),
                             num_td(fnum(r.get("measured_over_eq31"), 3)),
                             num_td(fnum(r.get("measured_over_sharp"), 3) if r.get("sharp_dt") else "–"),
                             num_td(fnum(r.get("sharp_finite_horizon_dt"))),
                             num_td(fnum(r.get("measured_over_sharp_finite_horizon"), 3)),
                             num_td(fnum(r.get("runs"))), num_td(fnum(r.get("wall_seconds"), 3))])
                key = f"stability.{r.get('case')}.{r.get('integrator')}"
                self.metric(key + ".measured_dt", r.get("measured_dt"), "value")
                self.metric(key + ".measured_over_sharp", r.get("measured_over_sharp"), "value")
            parts.append(table(["case", "integrator", "β", "measured Δt (s)", "eq. 31 Δt (s)",
                                "sharp β/ω_max (s)", "measured / eq. 31", "measured / sharp",
                                "sharp, finite horizon (s)", "measured / sharp (fin.)", "runs",
                                "wall (s)"], rows, 'id="stability-table"'))
        parts.append("<h3>Accuracy vs force evaluations (bar vibration)</h3>")
        rec = self.rec.get("compare:dynamic")
        if not ok(rec):
            parts.append(failed_box(rec, "dynamic integrator comparison"))
        else:
            parts.append(self.dynamic_block(rec["result"]["rows"]))
        parts.append("<h3>Quasi-static: time to steady state (clamped beam)</h3>")
        rec = self.rec.get("compare:quasistatic")
        if not ok(rec):
            parts.append(failed_box(rec, "quasi-static integrator comparison"))
        else:
            parts.append(self.quasistatic_block(rec["result"]["rows"]))
        parts.append("</section>")
        return "".join(parts)

    def dynamic_block(self, rows: list[dict]) -> str:
        series: dict[str, list[dict]] = {}
        for r in rows:
            label = r.get("integrator", "?") + ("" if r.get("table") in (None, "-") else f":{r['table']}")
            series.setdefault(label, []).append(r)
        fig, ax = plt.subplots(figsize=(7.2, 4.6))
        markers = "osD^v<>pP*X"
        for i, (label, rs) in enumerate(sorted(series.items())):
            rs = sorted(rs, key=lambda r: r.get("force_evaluations", 0))
            xs = [r.get("force_evaluations", 0) for r in rs]
            ys = [max(abs(r.get("error", 0.0)), 1e-16) for r in rs]
            ax.loglog(xs, ys, "-" + markers[i % len(markers)], ms=5, lw=1, label=label)
        ax.set_xlabel("force evaluations")
        ax.set_ylabel("free-end RMS error / (εL)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, ncol=2)
        ax.set_title("bar vibration: error vs cost", fontsize=10)
        img = self.savefig(fig, "integrators-dynamic.png")
        trows = []
        for r in rows:
            label = r.get("integrator", "?") + ("" if r.get("table") in (None, "-") else f":{r['table']}")
            trows.append([esc(label), num_td(fnum(r.get("dt"))), num_td(fnum(r.get("dt_over_eq31"), 3)),
                          num_td(fnum(r.get("error"))), num_td(fnum(r.get("error_vs_reference_pd"))),
                          num_td(fnum(r.get("force_evaluations"))), num_td(fnum(r.get("wall_seconds"), 3)),
                          esc(r.get("status", ""))])
            key = f"compare.dynamic.{label}.dt{fnum(r.get('dt_over_eq31'), 3)}"
            self.metric(key + ".error", r.get("error"), "error")
            self.metric(key + ".force_evaluations", r.get("force_evaluations"), "count")
        measure = rows[0].get("error_measure", "") if rows else ""
        return (f'<img src="{img}" alt="integrator accuracy vs cost">'
                f'<p class="note">error measure: {esc(measure)}; error vs the modal series includes '
                "the PD model's own (spatial) error, which is the floor the curves reach.</p>" +
                table(["integrator", "Δt (s)", "Δt / eq. 31", "error vs modal series",
                       "error vs PD reference", "force evaluations", "wall (s)", "status"], trows))

    def quasistatic_block(self, rows: list[dict]) -> str:
        trows, labels, walls, fevals = [], [], [], []
        for r in rows:
            label = r.get("integrator", "?") + ("" if r.get("table") in (None, "-") else f":{r['table']}")
            if r.get("adaptive"):
                label += " (adaptive)"
            labels.append(label)
            walls.append(float(r.get("wall_seconds") or 0))
            fevals.append(float(r.get("force_evaluations") or 0))
            trows.append([esc(label), num_td(fnum(r.get("dt"))), num_td(fnum(r.get("steps"))),
                          num_td(fnum(r.get("force_evaluations"))), num_td(fnum(r.get("wall_seconds"), 3)),
                          num_td(fnum(r.get("midspan_deflection"))), num_td(pct(r.get("error"))),
                          num_td(fnum(r.get("residual"))), esc(r.get("status", ""))])
            key = f"compare.quasistatic.{label}"
            self.metric(key + ".wall_seconds", r.get("wall_seconds"), "time", abs_tol=0.5)
            self.metric(key + ".error", r.get("error"), "error")
        fig, ax = plt.subplots(figsize=(7.2, 0.5 + 0.45 * max(len(labels), 1)))
        ax.barh(labels, walls, color="#4a78b5")
        for i, (w, f) in enumerate(zip(walls, fevals)):
            ax.text(w, i, f"  {w:.1f} s, {int(f)} evals", va="center", fontsize=8)
        ax.set_xlabel("wall time to steady state (s)")
        ax.invert_yaxis()
        ax.set_xlim(0, max(walls + [1]) * 1.45)
        ax.set_title("clamped beam: time to steady state", fontsize=10)
        img = self.savefig(fig, "integrators-quasistatic.png")
        fastest = min(range(len(walls)), key=lambda i: walls[i]) if walls else None
        reading = ""
        if fastest is not None and rows:
            ok_rows = [i for i, r in enumerate(rows) if r.get("status") == "converged"]
            if ok_rows:
                fastest = min(ok_rows, key=lambda i: walls[i])
            ref = next((i for i, r in enumerate(rows) if r.get("integrator") == "damped-euler"), None)
            reading = f"Fastest to steady state: {labels[fastest]} ({walls[fastest]:.1f} s"
            if ref is not None and walls[fastest] > 0:
                reading += f", {walls[ref] / walls[fastest]:.2g}× faster than damped Euler"
            reading += ")."
        return (f'<img src="{img}" alt="time to steady state">' +
                (f'<p class="reading">{esc(reading)}</p>' if reading else "") +
                table(["integrator", "Δt (s)", "steps", "force evaluations", "wall (s)",
                       "midspan deflection (m)", "vs damped Euler", "residual", "status"], trows))

    # ---------------------------------------------------------------------------------------
    def performance(self) -> str:
        parts = ['<section id="performance"><h2>Performance</h2>',
                 "<h3>Bond updates per second by stretch measure (Miranda Table 2, re-measured)</h3>"]
        rec = self.rec.get("bench")
        libpd_1t = None
        if not ok(rec):
            parts.append(failed_box(rec, "pd bench"))
        else:
            runs = rec["result"]["runs"]
            by = {(r["stretch"], r["threads_requested"]): r for r in runs}
            rows = []
            for s in ("exact", "modified", "fast"):
                r1, r2 = by.get((s, 1)), by.get((s, 2))
                base = by.get(("exact", 1))
                rate1 = r1 and r1.get("bond_updates_per_second")
                rate2 = r2 and r2.get("bond_updates_per_second")
                rows.append([esc(s), num_td(fnum(rate1)), num_td(fnum(rate2)),
                             num_td(f"{rate2 / rate1:.2f}×" if rate1 and rate2 else "–"),
                             num_td(f"{rate1 / base['bond_updates_per_second']:.2f}" if rate1 and base else "–"),
                             num_td(fnum(r1 and r1.get("seconds"), 3)), esc((r1 or {}).get("kernel", ""))])
                for t, r in ((1, r1), (2, r2)):
                    if r:
                        self.metric(f"bench.{s}.t{t}.bond_updates_per_second", r.get("bond_updates_per_second"), "rate")
            libpd_1t = by.get(("exact", 1))
            r0 = runs[0]
            parts.append(f'<p class="note">Scene <code>{esc(rec["result"]["scene"])}</code>: '
                         f"{fnum(r0.get('particles'))} particles, {fnum(r0.get('bonds'))} bonds; "
                         f"median of {r0.get('repeats')} repeats of {r0.get('steps')} force evaluations; "
                         f"load average during the stage {esc(rec['result'].get('loadavg'))}.</p>")
            parts.append(table(["stretch", "1 thread (bond updates/s)", "2 threads (bond updates/s)",
                                "2 vs 1 thread", "1 thread vs exact", "1-thread median (s)", "kernel"],
                               rows, 'id="bench-table"'))
            fig, ax = plt.subplots(figsize=(6.4, 3.2))
            xs = range(3)
            for off, t, col in ((-0.2, 1, "#4a78b5"), (0.2, 2, "#e08a2a")):
                ax.bar([x + off for x in xs],
                       [(by.get((s, t)) or {}).get("bond_updates_per_second", 0) / 1e6 for s in ("exact", "modified", "fast")],
                       width=0.4, color=col, label=f"{t} thread{'s' if t > 1 else ''}")
            ax.set_xticks(list(xs), ["exact", "modified", "fast"])
            ax.set_ylabel("million bond updates / s")
            ax.legend(fontsize=8)
            ax.grid(alpha=0.3, axis="y")
            parts.append(f'<img src="{self.savefig(fig, "bench-stretch.png")}" alt="bond updates per second">')
        parts.append("<h3>Cost of each effect (pd-kernel-bench)</h3>")
        parts.append(self.kernel_block())
        parts.append("<h3>LAMMPS peri/pmb beside libpd (Model A, 1 thread)</h3>")
        parts.append(self.lammps_block(libpd_1t))
        parts.append("<h3>Bonds per particle (infinite lattice) beside Miranda Table 1</h3>")
        parts.append(self.bonds_block())
        parts.append("</section>")
        return "".join(parts)

    def kernel_block(self) -> str:
        rec = self.rec.get("kernel")
        if not ok(rec):
            return failed_box(rec, "pd-kernel-bench")
        benches = [b for b in rec["result"]["benchmarks"]
                   if b.get("run_type", "iteration") == "iteration" or b.get("aggregate_name") == "median"]
        if not benches:
            return '<p class="fail">pd-kernel-bench returned no benchmarks</p>'
        unit_scale = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}

        def secs(b: dict) -> float:
            return float(b["real_time"]) * unit_scale.get(b.get("time_unit", "ns"), 1e-9)

        base = next((b for b in benches if "elastic_exact" in b["name"]), benches[0])
        rows = []
        for b in benches:
            rate = b.get("bond_updates_per_second")
            rows.append([esc(b["name"].replace("/real_time", "")), num_td(fnum(secs(b) * 1e3, 4)),
                         num_td(fnum(rate)), num_td(f"{secs(b) / secs(base):.2f}×")])
            nm = b["name"].replace("/real_time", "")
            self.metric(f"kernel.{nm}.seconds", secs(b), "time", abs_tol=0.0)
            if rate:
                self.metric(f"kernel.{nm}.bond_updates_per_second", rate, "rate")
        ctx = rec["result"].get("context", {})
        return (f'<p class="note">Google Benchmark, {esc(ctx.get("num_cpus", "?"))} CPUs, load '
                f'{esc(ctx.get("load_avg", "?"))}; relative cost against '
                f"<code>{esc(base['name'].replace('/real_time', ''))}</code> (the plain elastic "
                "kernel through the dispatcher).</p>" +
                table(["benchmark", "time per evaluation (ms)", "bond updates / s", "relative cost"], rows,
                      'id="kernel-table"'))

    def lammps_block(self, libpd_1t: dict | None) -> str:
        rec = self.rec.get("lammps")
        if not ok(rec):
            return failed_box(rec, "LAMMPS peer benchmark")
        j = rec["result"]
        threads = j.get("threads", {})
        rows = []
        for t, r in sorted(threads.items()):
            rows.append([f"LAMMPS peri/pmb ({esc(t)} thread{'s' if str(t) != '1' else ''})",
                         num_td(fnum(j.get("atoms"))), num_td(fnum(j.get("bonds_unordered"))),
                         num_td(fnum(r.get("bond_updates_per_second"))),
                         num_td(fnum(r.get("ns_per_bond_update_pair"), 3)),
                         num_td(fnum(r.get("median_pair_cpu_percent"), 3))])
            self.metric(f"lammps.t{t}.bond_updates_per_second", r.get("bond_updates_per_second"), "rate")
        diag = j.get("diagnostic_1_thread_bond_loop_only")
        if isinstance(diag, dict):
            rows.append(["LAMMPS, bond loop only (no contact; diagnostic)", num_td(fnum(j.get("atoms"))),
                         num_td(fnum(j.get("bonds_unordered"))), num_td(fnum(diag.get("bond_updates_per_second"))),
                         num_td(fnum(diag.get("ns_per_bond_update_pair"), 3)),
                         num_td(fnum(diag.get("median_pair_cpu_percent"), 3))])
        ratio = ""
        if libpd_1t:
            r = libpd_1t.get("bond_updates_per_second")
            rows.append(["libpd pd bench (exact stretch, 1 thread)", num_td(fnum(libpd_1t.get("particles"))),
                         num_td(fnum(libpd_1t.get("bonds"))), num_td(fnum(r)),
                         num_td(fnum(1e9 / r, 3) if r else "–"), "–"])
            l1 = threads.get("1", {}).get("bond_updates_per_second")
            if r and l1:
                ratio = (f'<p class="reading">libpd (exact stretch, 1 thread) does {r / l1:.2f}× the bond '
                         "updates per second of LAMMPS peri/pmb (1 thread) on the same Model A lattice.</p>")
        note = (f'<p class="note">LAMMPS {esc(j.get("lammps_version"))} (Debian '
                f'{esc(j.get("debian_package_version"))}), {esc(j.get("steps"))} steps × '
                f'{esc(j.get("repetitions"))} repetitions; {esc(j.get("omp_note", ""))}. '
                "LAMMPS counts a bond once per step (unordered pairs), as libpd does; its pair time "
                "includes its contact loop; CPU % shows how much of a core the run actually got on "
                "the shared machine.</p>")
        return note + table(["code", "particles", "bonds", "bond updates / s", "ns per bond update",
                             "CPU %"], rows, 'id="lammps-table"') + ratio

    def bonds_block(self) -> str:
        rec = self.rec.get("verify:bond-count")
        if not ok(rec):
            return failed_box(rec, "bond-count case (bonds per particle)")
        t = rec["result"].get("bonds_per_particle_infinite_lattice") or []
        rows = [[num_td(fnum(r.get("horizon_factor"))), num_td(fnum(r.get("bonds_per_particle_strict"))),
                 num_td(fnum(r.get("bonds_per_particle_inclusive"))), num_td(fnum(r.get("miranda_table1"))),
                 num_td(fnum(r.get("eq37"), 5))] for r in t]
        for r in t:
            self.metric(f"bond_count.m{r.get('horizon_factor')}.inclusive", r.get("bonds_per_particle_inclusive"), "count")
        return ('<p class="note">Unordered bonds per particle of the infinite cubic lattice for '
                "δ = m λ; strict |ξ| &lt; δ and inclusive |ξ| ≤ δ, beside Miranda's Table 1 and eq. 37.</p>" +
                table(["δ / λ", "strict", "inclusive", "Miranda Table 1", "eq. 37"], rows, 'id="bonds-table"') +
                f'<p class="note">{esc(rec["result"].get("note", ""))}</p>')

    # ---------------------------------------------------------------------------------------
    def stage_table(self) -> str:
        rows = []
        total_fresh = sum(r.get("seconds", 0) for r in self.rec.values() if not r.get("cached"))
        total_all = sum(r.get("seconds", 0) for r in self.rec.values())
        groups: dict[str, float] = {}
        for r in self.rec.values():
            groups[r.get("group", "?")] = groups.get(r.get("group", "?"), 0) + r.get("seconds", 0)
        for name, r in self.rec.items():
            st = r.get("status")
            cls = "pass" if st == "ok" else "fail"
            rows.append([f"<code>{esc(name)}</code>", f'<span class="{cls}">{esc(st)}</span>',
                         num_td(f"{r.get('seconds', 0):.1f}"), "cached" if r.get("cached") else "ran",
                         "<br>".join(f"<code>{esc(' '.join(c))}</code>" for c in r.get("commands", [])),
                         esc((r.get("error") or "")[:300])])
        dom = ""
        if groups and total_all > 0:
            top = sorted(groups.items(), key=lambda kv: -kv[1])
            dom = ("<p class=\"reading\">Time (as recorded when each stage last ran): " +
                   ", ".join(f"{g} {s:.0f} s ({100 * s / total_all:.0f} %)" for g, s in top[:5]) +
                   f". <b>{esc(top[0][0])}</b> dominates. This run computed {total_fresh:.0f} s; "
                   f"the rest came from the cache.</p>")
        return ('<section id="stages"><h2>Stages and timings</h2>' + dom +
                table(["stage", "status", "seconds", "this run", "command", "error"], rows,
                      'id="stage-table"') + "</section>")


# ---- helpers -------------------------------------------------------------------------------------

def flatten(d: object, prefix: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    if isinstance(d, dict):
        for k, v in d.items():
            out.update(flatten(v, f"{prefix}{k}."))
    elif isinstance(d, list):
        pass
    else:
        out[prefix.rstrip(".")] = d
    return out


def short(v: object) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def sweep_error(r: dict) -> float | None:
    e = r.get("error_vs_fe")
    if isinstance(e, dict):
        vals = [abs(float(v)) for v in flatten(e).values()
                if isinstance(v, (int, float)) and not isinstance(v, bool)]
        return max(vals) if vals else None
    if isinstance(e, (int, float)):
        return abs(float(e))
    return None


def pareto(pts: list[tuple]) -> list[tuple]:
    front = []
    best = math.inf
    for p in sorted(pts, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def _as_float(v: object) -> float | None:
    if isinstance(v, bool):
        return None
    try:
        return float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return None


KNOB_FIELD = {"spacing": "spacing", "horizon_factor": "horizon_factor", "stretch": "stretch",
              "surface_correction": "surface_correction", "volume_correction": "volume_correction",
              "force_tolerance": "force_tolerance"}


def sweep_readings(pts: list[tuple]) -> list[str]:
    """One sentence per knob, computed from the rows (the baseline row joins every knob's series
    with its own setting of that knob)."""
    out = []
    base = next((p for p in pts if p[2] == "baseline"), None)
    by: dict[str, list[tuple]] = {}
    for p in pts:
        if p[2] != "baseline":
            by.setdefault(p[2], []).append(p)
    for knob, sel in sorted(by.items()):
        series = list(sel)
        if base is not None:
            bv = base[4].get(KNOB_FIELD.get(knob, knob), "baseline")
            series.append((base[0], base[1], knob, bv, base[4]))
        if len(series) < 2:
            continue
        nums = [_as_float(p[3]) for p in series]
        if knob in ("surface_correction", "volume_correction"):
            off = [p for p in series if str(p[3]).lower() in ("none", "off", "false")]
            on = [p for p in series if str(p[3]).lower() not in ("none", "off", "false")]
            if on and off:
                a, b = off[0], on[0]
                gain = a[1] / b[1] if b[1] > 0 else math.inf
                cost = b[0] / a[0] if a[0] > 0 else math.inf
                verdict = ("free accuracy" if gain > 1.05 and cost < 1.15 else
                           "buys accuracy at a cost" if gain > 1.05 else
                           "does not improve the error here")
                out.append(f"{knob.replace('_', ' ')} {short(b[3])}: error {pct(a[1])} without → "
                           f"{pct(b[1])} with ({gain:.2g}× less) for {cost:.2g}× the time — {verdict}.")
            continue
        if all(n is not None for n in nums):
            s2 = sorted(zip(nums, series), key=lambda t: t[0])
            if knob in ("spacing", "force_tolerance"):
                lo, hi = s2[-1][1], s2[0][1]     # coarsest/loosest -> finest/tightest
            else:
                lo, hi = s2[0][1], s2[-1][1]
            gain = lo[1] / hi[1] if hi[1] > 0 else math.inf
            cost = hi[0] / lo[0] if lo[0] > 0 else math.inf
            name = {"spacing": "refining λ", "horizon_factor": "a larger horizon factor δ/λ",
                    "force_tolerance": "a tighter force tolerance"}.get(knob, knob)
            if gain >= 1:
                out.append(f"{name} ({short(lo[3])} → {short(hi[3])}) buys {gain:.2g}× less error per "
                           f"{cost:.2g}× more time (error {pct(lo[1])} → {pct(hi[1])}).")
            else:
                out.append(f"{name} ({short(lo[3])} → {short(hi[3])}) makes the error {1 / gain:.2g}× LARGER "
                           f"for {cost:.2g}× the time (error {pct(lo[1])} → {pct(hi[1])}).")
            continue
        # categorical (stretch measure): each alternative against the baseline's choice
        if base is not None:
            ref = series[-1]
            for p in sel:
                gain = p[1] / ref[1] if ref[1] > 0 else math.inf
                cost = p[0] / ref[0] if ref[0] > 0 else math.inf
                out.append(f"{knob} {short(p[3])} instead of {short(ref[3])}: error {pct(ref[1])} → "
                           f"{pct(p[1])}, time ×{cost:.2g}.")
    best = min(pts, key=lambda p: p[1])
    out.append(f"Most accurate run: {best[2]} = {short(best[3])}, error {pct(best[1])} in {best[0]:.1f} s.")
    return out


def render(out: Path, records: dict[str, dict], env: dict, meta: dict) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    for f in out.glob("*.png"):
        f.unlink()
    page = Page(out, records, env, meta)
    text = page.render()
    tmp = out / "index.html.tmp"
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, out / "index.html")
    report = {
        "schema": "libpd-report/1",
        "environment": env,
        "meta": meta,
        "stages": {k: {kk: v.get(kk) for kk in ("group", "status", "seconds", "cached", "error", "commands")}
                   for k, v in records.items()},
        "figures": page.figures,
        "metrics": page.metrics,
        "data": {k: v.get("result") for k, v in records.items()},
    }
    tmp = out / "report.json.tmp"
    tmp.write_text(json.dumps(report, indent=1, default=str), encoding="utf-8")
    os.replace(tmp, out / "report.json")
    return report
