"""What every section of the page reads (the stage records, environment, meta and the case files)
and where its figures go."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from . import records as R  # noqa: E402
from .cases import Case  # noqa: E402


class Page:
    def __init__(self, out: Path, records: dict[str, dict], env: dict, meta: dict,
                 cases: dict[str, Case]):
        self.out = out
        self.rec = records
        self.env = env
        self.meta = meta
        self.cases = cases
        self.figures: list[str] = []

    def group(self, g: str) -> dict[str, dict]:
        return R.group(self.rec, g)

    def savefig(self, fig, name: str) -> str:
        path = self.out / name
        fig.savefig(path, dpi=110, bbox_inches="tight")
        plt.close(fig)
        self.figures.append(name)
        return name
