// What a bond-based model with a mesh body runs with instead of the lattice defaults (model.hpp).
#include "libpd/discretisation/model.hpp"

#include <string>

namespace pd {

std::string mesh_corrections_note(const ModelSpec& spec) {
  if (!spec.has_mesh_body() || spec.effects.bond_model == BondModel::virtual_fibres) {
    return "";
  }
  return std::string("surface ") + to_string(spec.surface_correction) + ", volume " +
         to_string(spec.volume_correction) +
         ": a mesh body is an unstructured set, so its bonds cannot take the lattice's gradient "
         "weights (docs/scenes.md, meshes)";
}

} // namespace pd
