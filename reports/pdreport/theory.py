"""Closed-form deflection lines of the beams (Euler–Bernoulli and Timoshenko, uniform load p).

Parameters come from the `theory` object of fem_reference/reference/NAME.json (L, E, G, I, A, kappa,
p_N_per_m; E_bending where the bending modulus is not E: plane strain's E/(1 − ν²)).  Deflections are
positive downward, as everywhere in the report.

Clamped–clamped beam, span L:
    w_EB(x) = p x² (L − x)² / (24 E I)                      (midspan p L⁴ / (384 E I))
    w_T(x)  = w_EB(x) + p x (L − x) / (2 κ G A)             (midspan + p L² / (8 κ G A))
Cantilever clamped at x = 0, free at x = L:
    w_EB(x) = p x² (6 L² − 4 L x + x²) / (24 E I)           (tip p L⁴ / (8 E I))
    w_T(x)  = w_EB(x) + p (L x − x² / 2) / (κ G A)          (tip + p L² / (2 κ G A))
"""
from __future__ import annotations


def _params(theory: dict) -> tuple[float, float, float, float, float, float, float]:
    p = float(theory["p_N_per_m"])
    length = float(theory["L"])
    e = float(theory.get("E_bending", theory["E"]))
    g = float(theory["G"])
    i = float(theory["I"])
    a = float(theory["A"])
    kappa = float(theory["kappa"])
    return p, length, e, g, i, a, kappa


def beam_kind(theory: dict) -> str | None:
    kind = str(theory.get("kind", "")).lower()
    if "clamped-clamped" in kind:
        return "clamped-clamped"
    if "cantilever" in kind:
        return "cantilever"
    return None


def beam_deflection(theory: dict, x: float) -> tuple[float, float]:
    """(Euler–Bernoulli, Timoshenko) deflection at x for the beam described by `theory`."""
    p, length, e, g, i, a, kappa = _params(theory)
    kind = beam_kind(theory)
    if kind == "clamped-clamped":
        eb = p * x * x * (length - x) ** 2 / (24 * e * i)
        shear = p * x * (length - x) / (2 * kappa * g * a)
    elif kind == "cantilever":
        eb = p * x * x * (6 * length**2 - 4 * length * x + x * x) / (24 * e * i)
        shear = p * (length * x - x * x / 2) / (kappa * g * a)
    else:
        raise ValueError(f"no beam formula for theory kind {theory.get('kind')!r}")
    return eb, eb + shear


def check_against_gold(theory: dict) -> float:
    """Largest relative difference between our closed forms and the gold file's point values
    (midspan resp. tip), so a formula slip shows up in the report instead of a wrong curve."""
    length = float(theory["L"])
    x = length / 2 if beam_kind(theory) == "clamped-clamped" else length
    eb, tim = beam_deflection(theory, x)
    return max(abs(eb / theory["euler_bernoulli"] - 1), abs(tim / theory["timoshenko"] - 1))
