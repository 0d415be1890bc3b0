"""The structure cases as their folders' verification/cases/NAME/case.yaml describe them (kind
`structure`): the files the C++ runner (verification/runner/structures.cpp) reads, read here too so the report restates none of
their facts (FE line files, line axes, quantity points, the paper's agreement level and figures)."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

CASES_DIR = Path(__file__).resolve().parents[2] / "verification" / "cases"


@dataclass(frozen=True)
class Quantity:
    name: str
    fe: str                                 # its key in the FE reference's quantities
    point: tuple[float, ...]


@dataclass(frozen=True)
class Line:
    name: str
    fe_csv: str                             # gold file in fem_reference/reference
    fe_run_csv: str | None                  # the same line as a pd-fem run writes it
    along: str                              # x, y or z
    through: tuple[float, ...]
    paper_figure: int | None                # Miranda et al. 2019 figure that shows this line

    def position_of(self, point: tuple[float, ...]) -> float | None:
        """Where `point` lies along the line, or None if it is off the line."""
        axis = "xyz".index(self.along)
        if any(abs(p - t) > 1e-9 for k, (p, t) in enumerate(zip(point, self.through)) if k != axis):
            return None
        return point[axis]


@dataclass(frozen=True)
class Case:
    name: str
    summary: str
    fe_reference: str
    quantities: tuple[Quantity, ...]
    lines: tuple[Line, ...]
    gate: dict[str, float]
    has_sweep: bool
    path: Path
    paper_agreement: float | None = None    # Miranda's own PD–FE agreement (the gates are issue 14's)

    def line(self, name: str) -> Line | None:
        return next((l for l in self.lines if l.name == name), None)


def _case(d: dict, path: Path) -> Case:
    return Case(
        name=d["case"], summary=d.get("summary", ""), fe_reference=d["fe_reference"],
        quantities=tuple(Quantity(q["name"], q["fe"], tuple(map(float, q["point"])))
                         for q in d.get("quantities") or []),
        lines=tuple(Line(l["name"], l["fe_csv"], l.get("fe_run_csv"), l["along"],
                         tuple(map(float, l["through"])), l.get("paper_figure"))
                    for l in d.get("lines") or []),
        gate={k: float(v) for k, v in (d.get("gate") or {}).items()},
        has_sweep=bool(d.get("sweep")), path=path,
        paper_agreement=float(d["paper_agreement"]) if "paper_agreement" in d else None)


def load(cases_dir: Path = CASES_DIR) -> dict[str, Case]:
    """Every case folder of kind `structure`, by case name, in folder-name order."""
    import yaml   # only here: `pd_report.py --compare` must run without PyYAML

    out = {}
    for f in sorted(cases_dir.glob("*/case.yaml")):
        d = yaml.safe_load(f.read_text())
        if d.get("kind") != "structure":
            continue
        c = _case(d, f)
        out[c.name] = c
    return out


def in_listed_order(cases: dict[str, Case], listed: list[str]) -> list[str]:
    """The cases' names in the order `pd verify --list` gives them, unlisted ones last."""
    first = [c for c in listed if c in cases]
    return first + [c for c in cases if c not in first]
