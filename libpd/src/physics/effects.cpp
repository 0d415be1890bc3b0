#include "libpd/physics/effects.hpp"

namespace pd {

std::string to_string(StretchKind kind) {
  return std::string(name_of(kind));
}

std::vector<std::string> EffectSet::names() const {
  std::vector<std::string> out{"stretch:" + to_string(stretch)};
  if (bond_model != BondModel::micro_elastic) {
    out.emplace_back("bond-model:" + std::string(name_of(bond_model)));
  }
  if (damage) {
    out.emplace_back("damage");
  }
  if (plasticity) {
    out.emplace_back("plasticity");
  }
  if (per_bond_field) {
    out.emplace_back("per-bond-field");
  }
  if (damping) {
    out.emplace_back("damping");
  }
  if (body_force) {
    out.emplace_back("body-force");
  }
  return out;
}

} // namespace pd
