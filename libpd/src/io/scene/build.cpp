// Model building from a scene: the particles the reader generated are handed on rather than
// generated a second time.
#include "libpd/io/scene.hpp"

namespace pd {

Model build_model(const Scene& scene) {
  const ModelSpec& spec = scene.model;
  // Callers may change the lattice or bodies after loading (refinement studies do); the
  // particles then no longer belong to the model.
  const GeneratedParticles* generated = scene.particles.get();
  if (generated != nullptr && generated->dimension == spec.dimension &&
      generated->lattice == spec.lattice && generated->bodies == spec.bodies) {
    return build_model(spec, generated->particles);
  }
  return build_model(spec);
}

} // namespace pd
