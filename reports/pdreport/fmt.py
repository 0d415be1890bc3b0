"""Text formatting of numbers and strings, shared by the page and by the metric names of
report.json (a metric's name carries a formatted value, so both must format it the same way)."""
from __future__ import annotations

import html
import math


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


def short(v: object) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)
