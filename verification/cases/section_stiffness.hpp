// Stiffness of a PD cross-section relative to the continuum it discretises: an error budget for
// the structural cases that needs no run.
//
// A prism of the structure's cross-section, long enough along its span that the middle slice has
// a full horizon in both directions, is put under three uniform states: a curvature κ
// (u_span = κ·s·d, u_depth = −κ·s²/2 with s, d the span and depth coordinates from the section's
// centre), a transverse shear γ (u_depth = γ·s) and an axial strain ε (u_span = ε·s). The
// transverse displacements of the section are relaxed to the energy minimum (a small linear
// least-squares problem: by translation invariance along the span they are one vector per section
// particle), and the PD energy per unit length of the slice is divided by the continuum's:
// ½EIκ², ½GAγ², ½EAε² for a beam. A plate is long in the width direction too; its section is one
// column with ε_width = 0 (cylindrical bending), so the references are ½·E/(1−ν²)·t³/12·κ²,
// ½Gtγ² and ½·E/(1−ν²)·t·ε² per unit width.
//
// The energies use the model's own bond stiffnesses (corrections included), linearised stretch
// s = ξ·Δu/|ξ|² and the energy density ¼·Σ_j c_ij V_j |ξ| s² of a particle, so the result is that
// of the scene's settings. What it shows: a bond's stretch is the strain at its midpoint (for the
// curvature field above it is κ·d̄·n_span² with d̄ the mean depth of the two ends), so bonds that
// cross the thickness sample the curvature nearer the neutral axis than their particles; when δ is
// comparable with the thickness that costs bending stiffness that corrections calibrated on
// uniform strain cannot see. Effects of the supports, the load and the ends are not included.
#pragma once

#include "libpd/discretisation/model.hpp"

#include <cstddef>
#include <string>

namespace pd::verification {

struct SectionStiffness {
  double bending = 0;  ///< PD / continuum bending stiffness
  double shear = 0;    ///< PD / continuum stiffness under uniform transverse shear
  double membrane = 0; ///< PD / continuum axial stiffness
  std::size_t section_particles = 0;
};

/// Axis index of "x", "y" or "z"; throws std::runtime_error for anything else.
int axis_of(const std::string& name);

/// Section stiffness of `body` (its first box) in the scene model `spec`. `span` is the axis along
/// which the structure is long, `depth` the bending (load) direction; `plate` makes the third
/// axis long as well. Supports and loads of `spec` are ignored. Throws std::runtime_error for a 2D
/// or 1D model or axes that are not distinct.
SectionStiffness section_stiffness(const ModelSpec& spec, const BodySpec& body, int span, int depth,
                                   bool plate);

} // namespace pd::verification
