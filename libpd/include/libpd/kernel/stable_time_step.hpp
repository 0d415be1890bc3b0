// Stable time step of explicit integration (Miranda eq. 31, after Silling & Askari 2005):
//   Δt_i = sqrt( 2ρ_i / Σ_p V_p |C(ξ_ip)| ),   |C| = c_ip/|ξ_ip|,
// evaluated for every particle over its own bonds (so with several materials or corrections the
// stiffest bonds govern) and minimised over particles. It is a Gershgorin-type bound: the true
// limit of central differences is 2/ω_max, which is never smaller.
#pragma once

#include "libpd/discretisation/model.hpp"

#include <vector>

namespace pd {

std::vector<double> stable_time_step_per_particle(const Model& model);
/// min over particles of eq. 31; +inf for a model without bonds.
double stable_time_step(const Model& model);

} // namespace pd
