// Bond-based material constants: micromodulus c and critical stretch s0 from engineering data.
//
// Bond-based PD has a single elastic constant, so the Poisson ratio is fixed by the dimension
// (Silling 2000): 1/4 in 3D and plane strain, 1/3 in plane stress; in 1D it is meaningless.
// We match Young's modulus E of the fixed-ν material, which in 3D is the same as matching the
// bulk modulus k (Miranda et al. 2019, eq. 8: c = 18k/(πδ⁴) with k = E/(3(1-2ν)), ν = 1/4 gives
// c = 12E/(πδ⁴)).
#pragma once

#include "libpd/core/names.hpp"

#include <optional>
#include <string>

namespace pd {

/// How a 2D model interprets its out-of-plane direction.
enum class PlaneMode { plane_stress, plane_strain };

template <>
struct EnumName<PlaneMode> {
  static constexpr NameTable<PlaneMode, 2> table{{
      {"stress", PlaneMode::plane_stress, "plane stress: bond-based ν = 1/3"},
      {"strain", PlaneMode::plane_strain, "plane strain: bond-based ν = 1/4"},
  }};
};

/// The spatial setting of a model: dimension 1, 2 or 3, plus the 2D assumption and the
/// thickness (2D) or cross-section area (1D) that turn a lattice cell into a volume.
struct ModelDimension {
  int dim = 3;
  PlaneMode plane = PlaneMode::plane_stress;
  double thickness = 1.0;     ///< 2D only [m]
  double cross_section = 1.0; ///< 1D only [m²]

  bool operator==(const ModelDimension&) const = default;
};

struct Material {
  std::string name;
  double youngs_modulus = 0;   ///< E [Pa]
  double poisson_ratio = 0.25; ///< ν as given by the user (bond-based PD cannot honour all values)
  double density = 0;          ///< ρ [kg/m³]
  std::optional<double> fracture_energy;  ///< G0 [J/m²]; with it s0 is derived (eq. 11)
  std::optional<double> critical_stretch; ///< s0, given directly
  std::optional<double> yield_stretch;    ///< s_Y (eq. 15); virtual fibres: ε_yield (eq. 111)
  /// δ_e [m], virtual fibres only: an arm fails once its plastic elongation exceeds it
  /// (Olsson et al. 2021, eq. 118).
  std::optional<double> elongation_limit;
  /// Multiplies c. Used for deliberately stiff regions (Miranda §5.2.2 machine plates).
  double stiffness_factor = 1.0;
};

/// Poisson ratio that bond-based PD represents in this setting (nullopt in 1D).
std::optional<double> bond_based_poisson_ratio(const ModelDimension& d);

/// Micromodulus c [N/m⁶ in 3D] for Young's modulus E and horizon δ.
///  3D:           c = 12E/(πδ⁴)          (Miranda eq. 8 with ν = 1/4)
///  plane stress: c = 9E/(π t δ³)        (Ha & Bobaru 2010, ν = 1/3)
///  plane strain: c = 48E/(5π t δ³)      (Ha & Bobaru 2010, ν = 1/4)
///  1D:           c = 2E/(A δ²)          (Bobaru et al. 2009)
/// In 2D and 1D the 1/t and 1/A factors make c·V_j (V_j = λ²t or λA) independent of t and A.
double micromodulus(const ModelDimension& d, double youngs_modulus, double horizon);

/// Critical stretch from the fracture energy G0, found by equating the energy needed to break
/// every bond crossing a unit crack area with G0:
///  3D:           s0 = sqrt(10 G0 / (π c δ⁵))   (Miranda eq. 11)
///  plane stress: s0 = sqrt(4π G0 / (9 E δ))     (Ha & Bobaru 2010)
///  plane strain: s0 = sqrt(5π G0 / (12 E δ))    (Ha & Bobaru 2010)
///  1D:           s0 = sqrt(3 G0 / (E δ))        (Bobaru et al. 2009)
double critical_stretch_from_fracture_energy(const ModelDimension& d, double youngs_modulus,
                                             double horizon, double fracture_energy);

} // namespace pd
