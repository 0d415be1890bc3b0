// bond-count: Miranda et al. 2019 report 5229 particles / 313,710 bonds (Model A) and
// 36,465 / 2,627,528 (Model B) for node-based lattices with δ = 2√3 λ (Table 2). With δ = 2√3 λ
// the (±2, ±2, ±2) lattice offsets lie exactly on the horizon, so the count depends on whether
// |ξ| = δ is a bond. We report the strict (|ξ| < δ) and inclusive (|ξ| ≤ δ) counts; the paper's
// numbers fall between them, i.e. their code kept some but not all of the exactly-δ bonds — the
// signature of comparing round-off-perturbed floating-point distances with δ.
// Also: bonds per particle in an infinite lattice for δ/λ = 1…8 beside Miranda Table 1, whose
// values come from the approximation N/M ≈ (2/3)π(δ/λ)³ − 1/2 (eq. 37).
#include "libpd/discretisation/bond_family.hpp"
#include "libpd/io/scene.hpp"
#include "verification.hpp"

#include <cmath>
#include <fmt/format.h>
#include <numbers>

namespace pd::verification {

namespace {

struct Counts {
  std::size_t particles = 0;
  std::size_t strict = 0;
  std::size_t inclusive = 0;
};

Counts count(const std::filesystem::path& scene_path) {
  const Scene scene = load_scene(scene_path.string());
  const auto& spec = scene.model;
  const ParticleSet ps = generate_lattice(spec.dimension, spec.lattice, spec.bodies);
  const double delta = spec.lattice.horizon();
  Counts c;
  c.particles = ps.size();
  c.strict =
      build_bond_family(ps.position, spec.dimension.dim, delta, HorizonRule::strict).bond_count();
  c.inclusive = build_bond_family(ps.position, spec.dimension.dim, delta, HorizonRule::inclusive)
                    .bond_count();
  return c;
}

/// Lattice offsets n ≠ 0 with |n| ≤ m (or < m), counted exactly in integers.
std::size_t infinite_lattice_family(int m, bool inclusive) {
  std::size_t count = 0;
  const long long m2 = static_cast<long long>(m) * m;
  for (long long i = -m; i <= m; ++i) {
    for (long long j = -m; j <= m; ++j) {
      for (long long k = -m; k <= m; ++k) {
        const long long r2 = i * i + j * j + k * k;
        if (r2 != 0 && (inclusive ? r2 <= m2 : r2 < m2)) {
          ++count;
        }
      }
    }
  }
  return count;
}

} // namespace

Json run_bond_count(const Context& ctx) {
  struct Paper {
    const char* name;
    const char* scene;
    std::size_t particles;
    std::size_t bonds;
  };
  const Paper papers[] = {{"model_a", "model-a-benchmark.yaml", 5229, 313710},
                          {"model_b", "model-b-lattice.yaml", 36465, 2627528}};
  Json out;
  out["case"] = "bond-count";
  out["quantity"] = "particles and bonds (unordered pairs) of the paper's lattices";
  out["gate"] = "particles equal the paper's; strict <= paper bonds <= inclusive";
  bool passed = true;
  Json& pd_values = out["pd"];
  Json& reference = out["reference"];
  Json& error = out["error"];
  for (const Paper& p : papers) {
    const Counts c = count(ctx.scenes_dir / p.scene);
    const bool ok = c.particles == p.particles && c.strict <= p.bonds && p.bonds <= c.inclusive;
    passed = passed && ok;
    Json& v = pd_values[p.name];
    v["particles"] = c.particles;
    v["bonds_strict"] = c.strict;
    v["bonds_inclusive"] = c.inclusive;
    v["bonds_on_horizon"] = c.inclusive - c.strict;
    v["paper_share_of_on_horizon_bonds"] =
        static_cast<double>(p.bonds - c.strict) / static_cast<double>(c.inclusive - c.strict);
    reference[p.name]["particles"] = p.particles;
    reference[p.name]["bonds"] = p.bonds;
    error[std::string(p.name) + "_bonds_vs_inclusive"] =
        relative_error(static_cast<double>(c.inclusive), static_cast<double>(p.bonds));
    fmt::print("   {}: {} particles (paper {}), bonds strict {} <= paper {} <= inclusive {}: {}\n",
               p.name, c.particles, p.particles, c.strict, p.bonds, c.inclusive,
               ok ? "bracketed" : "NOT bracketed");
  }
  const double table1[] = {1.6, 16.3, 56.0, 134, 261, 452, 718, 1070};
  Json table = Json::array();
  fmt::print("   delta/lambda  strict  inclusive  Miranda Table 1  eq. 37\n");
  for (int m = 1; m <= 8; ++m) {
    const double strict = 0.5 * static_cast<double>(infinite_lattice_family(m, false));
    const double inclusive = 0.5 * static_cast<double>(infinite_lattice_family(m, true));
    const double eq37 = 2.0 / 3.0 * std::numbers::pi * m * m * m - 0.5;
    Json row;
    row["horizon_factor"] = m;
    row["bonds_per_particle_strict"] = strict;
    row["bonds_per_particle_inclusive"] = inclusive;
    row["miranda_table1"] = table1[m - 1];
    row["eq37"] = eq37;
    table.push_back(row);
    fmt::print("   {:>12} {:>7} {:>10} {:>16} {:>7.1f}\n", m, strict, inclusive, table1[m - 1],
               eq37);
  }
  out["bonds_per_particle_infinite_lattice"] = table;
  out["note"] =
      "Bonds are unordered pairs. With delta = 2*sqrt(3)*lambda the (2,2,2)-type offsets lie "
      "exactly on the horizon; the paper's counts lie between the strict and inclusive counts, so "
      "its code kept only part of those bonds, consistent with round-off in |xi| <= delta. libpd "
      "uses a 1e-9 relative guard band so the choice never depends on position. Table 1 values "
      "follow eq. 37 (a continuum approximation); exact lattice counts differ most at small "
      "delta/lambda.";
  out["passed"] = passed;
  return out;
}

PD_VERIFICATION_RUN("bond-count", run_bond_count);

} // namespace pd::verification
