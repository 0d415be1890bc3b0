// What `pd info` and the run summary say of a bond-based model with a mesh body (model.hpp).
#include "libpd/discretisation/model.hpp"

#include <string>

namespace pd {

std::string mesh_corrections_note(const ModelSpec& spec) {
  if (!spec.has_mesh_body() || spec.effects.bond_model == BondModel::virtual_fibres) {
    return "";
  }
  return std::string("surface ") + to_string(spec.surface_correction) + ", volume " +
         to_string(spec.volume_correction) +
         (spec.volume_correction == VolumeCorrection::gradient
              ? ": a mesh body is an unstructured set, so each particle's gradient weights are "
                "solved over its own bonds (docs/scenes.md, meshes)"
              : ": a mesh body is an unstructured set (docs/scenes.md, meshes)");
}

} // namespace pd
