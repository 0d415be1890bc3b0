// The round-off floor of the residual force: how small ‖V (b(y) + b_ext)‖ can get in double
// precision, so that a steady-state tolerance or a Newton iteration does not ask for less.
//
// The state is stored as positions y = X + u, each coordinate to within half an ulp of its own
// magnitude (ulp(y) ≈ 2.2e-16 |y|, with |y| the distance from the origin, not the displacement).
// The exact equilibrium y* is therefore not representable: the nearest state differs by δy, and
// near equilibrium the kernel's force density is linear, b(y* + δy) = −K δy with K the linearised
// operator (linear_operator.hpp): bond ij contributes k_ij n (n·(δy_j − δy_i)), k_ij = c_ij
// V_j/|ξ|. With δy uniform in ±ulp/2 (variance ulp²/12 per coordinate, independent), particle i's
// error has, in component a,
//   E δb_ia² = Σ_c (K_ii)_ac² σ_ic² + Σ_j k_ij² n_a² Σ_c n_c² σ_jc² + Σ_j (k_ij |ξ_ij| u n_a)²,
// the last term the kernel's own arithmetic: the stretch |y_j − y_i|/|ξ| − 1 is formed with a
// relative error ~u = 2^-53 in the length, an absolute error ~u in the stretch. (The summation of
// the bond forces adds u Σ_j |f_ij|, some 1e-13 of the load at the strains of a structure, so it
// is left out.) The position term dominates once |y| ≫ |ξ|: the floor grows with the distance of
// the body from the origin and with E/λ², and is independent of the load, so relative to the
// load it is largest for light loads on stiff, finely resolved bodies: a 2D steel cantilever under
// its own weight at λ = 1 cm floors at 1.7e-6 of the load, and its relaxations settle at 1e-5
// (ADR) to 5e-5 (damped Euler), above the default tolerance 1e-6.
//
// Dependants (mirror images, ghosts, extrapolated clamps) have their forces folded onto their
// sources; their standard deviations are folded with |a| (fold_mirror_bounds), an upper bound for
// the correlated sum. The floor is the norm of V_i times these standard deviations over the free
// degrees of freedom: the rms residual of the representable state nearest the equilibrium. The
// static solver's Newton iteration stalls at 0.72–0.93× it (2D and 3D cantilevers, the clamped
// beam, a body 100 m from the origin; steady_state_test). A relaxation that rounds its positions at
// every step settles higher (Integrator::round_off_amplification).
#pragma once

#include "libpd/discretisation/model.hpp"

#include <cstdint>
#include <vector>

namespace pd {

/// A steady-state tolerance or an accepted Newton residual stays this many times above the
/// estimated floor, so that the residual of a converged state meets it however the last ulps fall
/// (measured: 0.72–0.93× the estimate after the static solver's Newton iteration stalls).
inline constexpr double round_off_margin = 2.0;

/// The estimated round-off floor [N] of ‖V (b(y) + b_ext)‖ over the degrees of freedom with
/// held[d] = 0 (held: 3N flags, 1 for the dofs of supports and dependants, whose force entries
/// are reactions) at positions y (3N; the reference positions serve as well: the floor depends on
/// |y|, not on the small displacement).
double residual_round_off_floor(const Model& model, const double* y,
                                const std::vector<std::uint8_t>& held);

} // namespace pd
