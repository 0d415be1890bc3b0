// Scene files: the YAML description of a run (model, solver, probes, output).
//
// Every key is declared in a schema with its type, unit, range and documentation, so that errors
// name file:line:column with a one-line fix hint and `pd run --print-defaults` can write a
// commented template. Loading never throws anything but SceneError.
#pragma once

#include "libpd/discretisation/model.hpp"
#include "libpd/time/simulation.hpp"

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace pd {

/// A position in a scene file (1-based line and column; 0 if unknown).
struct SourceMark {
  int line = 0;
  int column = 0;
};

/// A bad scene: message is "FILE:LINE:COLUMN: error: WHAT\n  hint: HOW TO FIX".
class SceneError : public std::runtime_error {
public:
  SceneError(std::string file, SourceMark mark, const std::string& what, const std::string& hint);
  const std::string& file() const { return file_; }
  SourceMark mark() const { return mark_; }

private:
  std::string file_;
  SourceMark mark_;
};

struct ProbeSpec {
  std::string name;
  /// Where: the particle nearest a point, the mean over a region, or a support's particles.
  enum class Kind { point, region, support } kind = Kind::point;
  /// What: a displacement component; the force a support exerts on the body; the normal stress
  /// σ_cc from the bond forces; the damage index (eq. 13).
  enum class Quantity { displacement, reaction, stress, damage } quantity = Quantity::displacement;
  Vec3 point{0, 0, 0};
  Region region;
  std::string support; ///< Kind::support: the support's name
  int component = 0;   ///< 0, 1, 2 = x, y, z
};

template <>
struct EnumName<ProbeSpec::Quantity> {
  using Quantity = ProbeSpec::Quantity;
  static constexpr NameTable<Quantity, 4> table{{
      {"displacement", Quantity::displacement, "displacement component [m]"},
      {"reaction", Quantity::reaction, "force the support exerts on the body [N]"},
      {"stress", Quantity::stress, "normal stress σ_cc from the bond forces [Pa]"},
      {"damage", Quantity::damage, "damage index φ (eq. 13)"},
  }};
};

/// `solver.stop_when`: end a run when a probe shows that the specimen failed, with status
/// `failed` and exit code 0 (a fracture test that ends by breaking is a result, not an error).
struct StopWhenSpec {
  std::string probe;      ///< empty: no criterion
  double drops_below = 0; ///< stop when |value| < this × its peak |value| so far (0: unused)
  double exceeds = 0;     ///< stop when |value| > this (0: unused)
  bool enabled() const { return !probe.empty(); }
};

struct OutputSpec {
  std::size_t vtu_every = 0;     ///< steps between VTU files; 0: final state only
  std::size_t history_every = 0; ///< steps between probe history rows; 0: no history
  bool vtu = true;
};

/// Particles the reader generated (to check mirror supports), with the dimension, lattice and
/// bodies they were generated from.
struct GeneratedParticles {
  ModelDimension dimension;
  LatticeSpec lattice;
  std::vector<BodySpec> bodies;
  ParticleSet particles;
};

struct Scene {
  std::string path; ///< file it was read from
  std::string title;
  ModelSpec model;
  SolverSpec solver;
  StopWhenSpec stop_when;
  InitialSpec initial;
  std::vector<ProbeSpec> probes;
  OutputSpec output;
  std::vector<std::string> warnings; ///< "FILE:LINE:COL: warning: ..." lines
  /// Set when reading had to generate the particles; build_model(Scene) reuses them.
  std::shared_ptr<const GeneratedParticles> particles;
};

/// Read and check a scene. Throws SceneError for every problem it can detect without running,
/// including empty regions and loads or probes that select no particle.
/// Largest scene file read: a scene is a page of YAML; far larger input is a mistake (or
/// /dev/zero), and its values would be echoed in messages.
inline constexpr std::size_t max_scene_bytes = std::size_t{16} << 20;

Scene load_scene(const std::string& path);
/// Same, from text (tests); `name` stands in for the file name in messages.
Scene parse_scene(const std::string& text, const std::string& name);

/// build_model(scene.model), on the particles the reader generated if it did and the model's
/// dimension, lattice and bodies are still the ones they were generated from.
Model build_model(const Scene& scene);

/// A commented template listing every key with its default, unit and meaning.
std::string scene_template();

/// The scene reference in Markdown (docs/scene-reference.md): one table per section with every
/// key's type, unit, allowed values, default and meaning.
std::string scene_reference();

} // namespace pd
