// Stiffness of a PD cross-section relative to the continuum it discretises: an error budget for
// the structural cases that needs no run.
//
// A prism of the structure's cross-section, long enough along its span that the middle slice has
// a full horizon in both directions, is put under three uniform states: a curvature κ
// (u_span = κ·s·d, u_depth = −κ·s²/2 with s, d the span and depth coordinates from the section's
// centre), a transverse shear γ (u_depth = γ·s) and an axial strain ε (u_span = ε·s). The
// transverse displacements of the section are relaxed to the energy minimum (a small linear
// least-squares problem: by translation invariance along the span they are one vector per section
// cell), and the PD energy per unit length of the slice is divided by the continuum's:
// ½EIκ², ½GAγ², ½EAε² for a beam. A plate is long in the width direction too; its section is one
// column with ε_width = 0 (cylindrical bending), so the references are ½·E/(1−ν²)·t³/12·κ²,
// ½Gtγ² and ½·E/(1−ν²)·t·ε² per unit width. A 2D model is a beam whose width is the thickness t
// out of plane; its section is one column too, with E in plane stress and E/(1−ν²) in plane
// strain (ε_z = 0).
//
// The prism is built by build_model, the path every scene takes, so the section has the scene's
// surface and volume treatment: the default ghost layers (their displacements extrapolated from
// the section's relaxed body particles exactly as a run sets them, their bonds carrying half the
// energy), the `gradient` bond weights and the pruning of bonds without stiffness, or any older
// correction pair. The energy is W_c of the slice's particles, ghosts included, with the model's
// bond stiffnesses, the linearised stretch s = ξ·Δu/|ξ|² and the energy density ¼·Σ_j c_ij V_j
// |ξ| s² of a particle. What it shows: a bond's stretch is the strain at its midpoint (for the
// curvature field above it is κ·d̄·n_span² with d̄ the mean depth of the two ends), so bonds that
// cross the thickness sample the curvature nearer the neutral axis than their particles; when δ is
// comparable with the thickness that costs bending stiffness that corrections calibrated on
// uniform strain cannot see. Effects of the supports, the load and the ends are not included.
#pragma once

#include "libpd/discretisation/model.hpp"

#include <cstddef>
#include <optional>
#include <string>

namespace pd::verification {

struct SectionStiffness {
  double bending = 0;                ///< PD / continuum bending stiffness
  double shear = 0;                  ///< PD / continuum stiffness under uniform transverse shear
  double membrane = 0;               ///< PD / continuum axial stiffness
  std::size_t section_particles = 0; ///< body particles of one slice (ghosts not counted)
  double bending_reference = 0;      ///< the continuum's EI [N m²] (per unit width for a plate)
  double shear_reference = 0;        ///< the continuum's GA [N] (per unit width for a plate)
};

/// Axis index of "x", "y" or "z"; throws std::runtime_error for anything else.
int axis_of(const std::string& name);

/// Section stiffness of `body` (its first box) in the scene model `spec` (2D or 3D). `span` is
/// the axis along which the structure is long, `depth` the bending (load) direction (in 2D the
/// two in-plane axes); `plate` (3D only) makes the third axis long as well. Supports and loads of
/// `spec` are ignored. Throws std::runtime_error for a 1D model or axes that do not fit.
SectionStiffness section_stiffness(const ModelSpec& spec, const BodySpec& body, int span, int depth,
                                   bool plate);

/// How a beam is held and loaded, for Timoshenko's split of its deflection.
enum class BeamCase {
  cantilever_uniform, ///< one clamped end, uniform load: tip deflection
  cantilever_tip,     ///< one clamped end, point load at the free end
  clamped_uniform,    ///< both ends clamped, uniform load: midspan
  clamped_centre,     ///< both ends clamped, point load at midspan
  simple_uniform,     ///< simply supported, uniform load: midspan
  simple_centre,      ///< simply supported, point load at midspan
};

/// The words of a BeamCase ("cantilever, uniform load", …).
std::string to_string(BeamCase beam);

/// The beam case a scene describes along `span` (its first body's box, bending in `depth`), from
/// its supports and loads: an end is clamped by a mirror support across the span axis or by a
/// support fixing every component, and simply supported by one that fixes the depth component
/// only, each lying within one spacing of the end. One clamped end and a free one make a
/// cantilever, two clamped ends a clamped beam, two simple supports a simply supported one. A load
/// over at least 90 % of the span is uniform; one within a fifth of the span of the free end (a
/// cantilever) or of midspan (the others) is a point load. nullopt for anything else.
std::optional<BeamCase> beam_case_of(const ModelSpec& spec, int span, int depth);

/// Timoshenko's shear coefficient of a rectangle, as the FE reference takes it
/// (fem_reference/src/elastic_reference.cc).
inline constexpr double shear_coefficient = 5.0 / 6.0;

/// Timoshenko's shear deflection over the bending deflection of a beam of this section and `span`:
/// α·EI/(κ·GA·L²) with α = 4 (cantilever, uniform load), 3 (cantilever, tip load), 48 (clamped
/// both ends, uniform or centre load), 9.6 (simply supported, uniform), 12 (simply supported,
/// centre load).
double timoshenko_shear_ratio(const SectionStiffness& s, BeamCase beam, double span);

/// The deflection factor PD / continuum the section predicts for a beam whose shear deflection is
/// `shear_ratio` times its bending deflection: each part divided by its stiffness factor,
/// (1/bending + r/shear) / (1 + r).
double deflection_factor(const SectionStiffness& s, double shear_ratio);

} // namespace pd::verification
