// Scene files: the YAML description of a run (model, solver, probes, output).
//
// Every key is declared in a schema with its type, unit, range and documentation, so that errors
// name file:line:column with a one-line fix hint and `pd run --print-defaults` can write a
// commented template. Loading never throws anything but SceneError.
#pragma once

#include "libpd/discretisation/model.hpp"
#include "libpd/time/simulation.hpp"

#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
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

/// The components a probe can read, one word each: a displacement or reaction component (x, y,
/// z), a moment's axis, or a tensor component of stress or strain (x, y, z read as xx, yy, zz).
inline constexpr std::array<std::string_view, 9> probe_component_words{"x",  "y",  "z",  "xx", "yy",
                                                                       "zz", "xy", "yz", "zx"};
/// Tensor components 3, 4, 5 (xy, yz, zx) as index pairs; 0, 1, 2 are the diagonal.
inline constexpr std::array<std::array<int, 2>, 6> tensor_component_axes{
    {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {2, 0}}};

struct ProbeSpec {
  std::string name;
  /// Where: the particle nearest a point, the mean over a region, or a support's particles
  /// (`line` only while reading: a line becomes point probes).
  enum class Kind { point, region, support, line } kind = Kind::point;
  /// What: see EnumName<Quantity> below.
  /// (New words go last: a checkpoint's fingerprint holds the number.)
  enum class Quantity {
    displacement,
    reaction,
    stress,
    damage,
    moment,
    strain,
    von_mises,
    opening
  } quantity = Quantity::displacement;
  Vec3 point{0, 0, 0};
  Vec3 to{0, 0, 0};    ///< opening: the second point (the first is `point`)
  Vec3 about{0, 0, 0}; ///< moment: the point the moment is taken about
  Region region;
  std::string support; ///< Kind::support: the support's name
  /// A point of a line probe (`line: {from, to, points}`), which the reader writes as one point
  /// probe per point, named LINE[k]: the line's name, k, and the distance from `from` [m].
  std::string line;
  int line_index = -1;
  double line_distance = 0;
  /// 0, 1, 2 = x, y, z (a stress or strain: xx, yy, zz); 3, 4, 5 = xy, yz, zx
  int component = 0;
};

template <>
struct EnumName<ProbeSpec::Quantity> {
  using Quantity = ProbeSpec::Quantity;
  static constexpr NameTable<Quantity, 8> table{{
      {"displacement", Quantity::displacement, "displacement component [m]"},
      {"reaction", Quantity::reaction, "force the support exerts on the body [N]"},
      {"stress", Quantity::stress, "stress component σ_ab from the bond forces [Pa]"},
      {"damage", Quantity::damage, "damage index φ (eq. 13)"},
      {"moment", Quantity::moment,
       "moment about 'about' of the forces the support exerts on the body [N m]"},
      {"strain", Quantity::strain, "small-strain component ε_ab of the displacement field [-]"},
      {"von_mises", Quantity::von_mises, "von Mises stress of the bond-force stress [Pa]"},
      {"opening", Quantity::opening,
       "displacement of 'to' relative to 'point' along the line from 'point' to 'to' [m]"},
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
