"""The page's building blocks: style sheet, browser self-check script, tables and the box that
shows a failed or missing stage."""
from __future__ import annotations

from .fmt import esc

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
#scorecard-table{width:100%;font-size:13px} #scorecard-table td{overflow-wrap:anywhere}
#scorecard-table td.num{overflow-wrap:normal} #scorecard-table td.case{white-space:nowrap}
#scorecard-table td.kind{color:#555;font-size:12px} #scorecard-table td.gate-text{font-size:12px;
 color:#444;max-width:260px} #scorecard-table td.gate{white-space:nowrap}
td.over{color:#b3141a;font-weight:600} #summary-table{font-size:12px} td .wrap{white-space:normal;display:inline-block}
td.verdict{font-weight:700;text-align:center;white-space:nowrap}
.v-pass{background:#e2f4e5;color:#0a7a28} .v-fail{background:#fde2e2;color:#b3141a}
.v-info{background:#f1f1f4;color:#555}
.cases{display:flex;flex-wrap:wrap;gap:6px 18px} .case{flex:1 1 380px;min-width:0}
table.kv{font-size:12px;width:100%;table-layout:fixed} table.kv td{overflow-wrap:anywhere}
table.kv td:first-child{width:55%} details{margin:4px 0 10px}
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
  b.setAttribute('data-scorecard-rows',
    String(document.querySelectorAll('#scorecard-table tbody tr[data-case]').length));
  // Sideways scrolling: the page's own width against the window's, and the scorecard's against
  // the space it has (a table may overflow its box without widening the document).
  var sc=document.getElementById('scorecard-table');
  b.setAttribute('data-viewport-width', String(window.innerWidth));
  b.setAttribute('data-client-width', String(document.documentElement.clientWidth));
  b.setAttribute('data-document-width', String(document.documentElement.scrollWidth));
  b.setAttribute('data-scorecard-width', sc ? String(Math.ceil(sc.getBoundingClientRect().width)) : '-1');
  b.setAttribute('data-scorecard-room', sc ? String(sc.parentElement.clientWidth) : '-1');
  b.setAttribute('data-check', broken.length===0 ? 'images-ok' : 'images-broken');
}
window.addEventListener('load', pdCheckImages);
</script>
"""


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
