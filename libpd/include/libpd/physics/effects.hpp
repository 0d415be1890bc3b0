// The set of effects a run simulates. A scene declares them; the engine picks a force kernel
// compiled for exactly this set (see force_kernel.hpp), so an effect that is not listed costs no
// branch, memory or time in the bond loop.
#pragma once

#include "libpd/physics/fibres.hpp"
#include "libpd/physics/stretch.hpp"

#include <string>
#include <vector>

namespace pd {

struct EffectSet {
  /// What the bonds carry; `virtual_fibres` selects its own kernel (kernel/fibre_kernel.hpp).
  BondModel bond_model = BondModel::micro_elastic;
  StretchKind stretch = StretchKind::exact; ///< bond-law parameter
  bool damage = false;     ///< brittle bonds with critical stretch, damage index (eqs. 9–13)
  bool plasticity = false; ///< micro-plastic bonds with plastic stretch history (eqs. 14–16)
  /// Bond stiffness and strength stored per bond instead of one value for the whole body: needed
  /// for several materials, surface/volume corrections or varying particle volumes.
  bool per_bond_field = false;
  bool damping = false;    ///< kinematic damping in the integrator (Miranda §3.2)
  bool body_force = false; ///< external force density on particles

  /// Elastic bonds only (no damage, plasticity or virtual fibres): what
  /// `solver.small_displacements` can linearise.
  bool elastic_bonds_only() const {
    return !damage && !plasticity && bond_model != BondModel::virtual_fibres;
  }

  /// Names as printed in summaries, e.g. {"stretch:fast", "damage", "per-bond-field"}.
  std::vector<std::string> names() const;
};

std::string to_string(StretchKind kind);

} // namespace pd
