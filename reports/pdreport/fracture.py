"""The Fracture section: the fracture cases side by side, each with the scorecard's lines (quantity,
PD, reference, error, gate), its wall time and its verdict. The rows are the scorecard's own
(scorecard.entries, scorecard.rows_html), so the two cannot disagree; what else a case measured
(tip history, branching position, crack points) is in its own section under Cases."""
from __future__ import annotations

from . import scorecard
from .page import Page

# The runs of the fracture case folders (verification/cases/<folder>/case.yaml), in the order the
# section lists them: the quasi-static ones first, then the dynamic ones.
CASES = ("fracture-stop", "fracture-stop-convergence", "fracture-stop-biaxial",
         "fracture-stop-corrections", "fracture-stop-3d",
         "fracture-stop-3d-slab", "crack-opening", "dcb", "dcb-fine",
         "kalthoff-winkler", "kalthoff-winkler-fine", "glass-branching", "glass-branching-fine")


def section(page: Page) -> str:
    es = [e for e in scorecard.entries(page) if e.case in CASES]
    es.sort(key=lambda e: CASES.index(e.case))
    intro = ('<p class="note">The fracture cases: a crack that starts, runs, turns or splits, against '
             "a closed form, a bound or an experiment. The columns are the scorecard's.</p>")
    if not es:
        return ('<section id="fracture"><h2>Fracture</h2>' + intro +
                "<p><i>No fracture case is listed in this report.</i></p></section>")
    head = ("<tr><th>case</th><th>quantity</th><th>PD</th><th>reference</th><th>which</th>"
            "<th>error</th><th>gate</th><th>wall (s)</th><th>result</th></tr>")
    return ('<section id="fracture"><h2>Fracture</h2>' + intro +
            f'<table id="fracture-table"><thead>{head}</thead><tbody>' +
            "".join(scorecard.rows_html(e) for e in es) + "</tbody></table></section>")
