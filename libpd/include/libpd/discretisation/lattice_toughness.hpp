// The toughness of the discrete model: the stress intensity at which a straight crack runs through
// the lattice, over the K_Ic = √(E' G0) that the energy-derived critical stretch aims at.
//
// Why s0 from G0 alone is not enough: eq. 11 (and its 2D forms) makes the energy stored at s0 in
// the bonds crossing a unit area equal G0. A crack in a lattice of brittle bonds does not grow at
// that energy release rate: when the tip bond snaps, the bonds it leaves behind are loaded beyond
// what a smooth crack front would give them, and the next bond (often a diagonal reaching back
// over the broken column) needs a larger K than the first one did. This is lattice trapping
// (Thomson, Hsieh & Rana 1971): the crack runs only once K passes the largest value over one
// lattice period, so the discrete model is tougher than G0 says, by a factor that depends on the
// bond weights and the horizon in spacings m, not on λ. At the default m = 2√3 it is about 1.58
// with the `gradient` weights (stiffness on the bonds up to two spacings) and about 1.27 without
// volume weights; it does not fall under δ-refinement at fixed m, so a failure load converged in
// δ stayed 27–58 % above Griffith's (issue 36).
//
// The factor is measured, for the model's own lattice and corrections, on the boundary-layer
// problem of fracture mechanics: a square of half-width R = 10δ around a crack tip that lies on a
// cell face between two rows, the outer band (δ + λ wide) held at the mode-I displacement field of
// LEFM for K = K_Ic, re-centred on the current tip after every break. Bonds break one at a time,
// the most over-stretched first (sequentially linear: each break is followed by a new equilibrium;
// breaks are rank-one changes of the stiffness, solved with the Woodbury identity on one
// factorisation), and the factor is the largest load multiplier a break needs once the tip has
// moved past the first lattice periods (the crack's steady state). Dividing the energy-derived s0
// by it makes the model's crack run at K_Ic, so failure loads converge to LEFM as δ falls.
// The energy stored in the crossing bonds at this s0 is then G0 / factor²: the rest of G0 is what
// each snapping bond releases into its neighbours (dissipated dynamically or by the static
// solver's break events), which a global energy balance counts and a sum over bonds does not.
//
// Scope: two dimensions (plane stress and plane strain give the same factor, the computation is
// scale-free, so it depends only on m, the horizon rule and the corrections). It is cached per
// configuration; a computation takes about a second. In 1D there is no crack tip, and the 3D
// factor is not derived yet (lattice_toughness_ratio returns nullopt for both).
#pragma once

#include "libpd/discretisation/model.hpp"

#include <optional>

namespace pd {

/// K at which a straight crack along a lattice axis runs in `spec`'s lattice with its
/// corrections, over √(E' G0) (E' = E in plane stress, E/(1 − ν²) in plane strain), for the
/// energy-derived s0 (critical_stretch_from_fracture_energy). nullopt outside 2D.
/// Computed in plane stress and cached per (m, horizon rule, corrections).
std::optional<double> lattice_toughness_ratio(const ModelSpec& spec);

/// The computation behind it in `spec`'s own plane mode, not cached (2D only).
double lattice_toughness_ratio_in(const ModelSpec& spec);

} // namespace pd
