// Spectral estimates of the linearised PD operator (Miranda eq. 30, bond operator
// C = c ξ⊗ξ/|ξ|³ per unit neighbour volume) on the free degrees of freedom: the largest frequency
// ω_max that bounds explicit time steps, and the spectral measure of a perturbation, both by
// Lanczos iteration. The stability predictions of time/stability.hpp are built on them.
#pragma once

#include "libpd/discretisation/model.hpp"

#include <vector>

namespace pd {

struct FrequencyEstimate {
  double omega_max = 0; ///< [rad/s] (ADR: per unit fictitious time)
  int iterations = 0;
  double change = 0; ///< relative change of ω_max² over the last 10 iterations
};

/// ω_max² = largest eigenvalue of M⁻¹K on the free degrees of freedom (constraints removed), K
/// the linearised bond operator at the reference configuration (broken bonds left out). `mass`
/// is the mass density per degree of freedom (3N); empty: the material density. Lanczos
/// iteration (a Krylov acceleration of the power iteration) on M^{-1/2} K M^{-1/2}.
FrequencyEstimate max_frequency(const Model& model, const std::vector<double>& mass = {},
                                int max_iterations = 300);

/// Spectral measure of a displacement perturbation of the free degrees of freedom: nodes ω_k²
/// of M⁻¹K and the strain energy e_k of the perturbation near each node (Gauss quadrature from
/// `iterations` Lanczos steps started at the perturbation; Σ e_k = its strain energy).
struct PerturbationSpectrum {
  std::vector<double> omega_squared;
  std::vector<double> energy;
};
PerturbationSpectrum perturbation_spectrum(const Model& model, const std::vector<double>& du,
                                           int iterations = 200);

} // namespace pd
