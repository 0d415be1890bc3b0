// The energy invariant behind s0 (issue 36, item 1): separating a model along a plane must cost G0
// per unit area. For every bond that crosses the plane this sums the energy it holds at its own
// breaking stretch, ½ c_ij s0_ij² |ξ| V_i V_j (Miranda–Orr–Williams eq. 11 is this sum taken as
// an integral), with the model's per-bond stiffness and s0, and divides by the plane's area.
// A bond into a ghost or a clamp image has only the body's directed bond, which carries the whole
// pair force in the kernel, so it counts once; a pair of body particles counts once over its two
// directed bonds.
//
// The models are built from scene text, so the treatments are the library's defaults unless a
// row names another pair. `Measure` prints the table and gates nothing; `Defaults…` gates the
// rows that hold today (see the report of issue 36 for the rows that do not).
#include "libpd/discretisation/model.hpp"
#include "libpd/io/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr double lambda = 1e-3, youngs = 72e9, g0 = 10.0, thickness = 1e-3, section = 1e-6;

struct Plane {
  const char* name;
  pd::Vec3 point;  ///< a point on the plane
  pd::Vec3 normal; ///< unit normal
  pd::Vec3 along;  ///< unit tangent in the plane (2D and 3D), for the window
  double half;     ///< half-length of the window along `along` (≤ 0: the whole plane)
  pd::Vec3 along2; ///< second tangent (3D)
  double half2;    ///< half-length along `along2` (3D)
  double area;     ///< the body's area the window covers
};

double dot(const pd::Vec3& a, const pd::Vec3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// A window spanning whole lattice periods counts each bond's repeats once. Its centre is moved
/// off the lattice's symmetric points so that no crossing point lies on an edge, where rounding
/// would count it twice or not at all.
bool inside(double t, double half) {
  const double shifted = t - 0.137 * lambda;
  return shifted >= -half && shifted < half;
}

/// Energy at breaking of the bonds crossing `p`, per unit area, divided by G0.
double crossing_ratio(const pd::Model& m, const Plane& p) {
  const auto& f = m.family;
  const auto& x = m.particles.position;
  double energy = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const pd::Vec3 di{x[i][0] - p.point[0], x[i][1] - p.point[1], x[i][2] - p.point[2]};
    const double si = dot(di, p.normal);
    for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
      const std::size_t j = f.neighbour[k];
      const pd::Vec3 dj{x[j][0] - p.point[0], x[j][1] - p.point[1], x[j][2] - p.point[2]};
      const double sj = dot(dj, p.normal);
      if (!((si < 0 && sj > 0) || (si > 0 && sj < 0))) {
        continue;
      }
      const double t = si / (si - sj); // where the bond meets the plane
      const pd::Vec3 c{di[0] + t * (dj[0] - di[0]), di[1] + t * (dj[1] - di[1]),
                       di[2] + t * (dj[2] - di[2])};
      if (p.half > 0 && !inside(dot(c, p.along), p.half)) {
        continue;
      }
      if (p.half2 > 0 && !inside(dot(c, p.along2), p.half2)) {
        continue;
      }
      bool reverse = false;
      for (std::size_t q = f.offsets[j]; q < f.offsets[j + 1]; ++q) {
        reverse = reverse || f.neighbour[q] == i;
      }
      const double stiffness = m.field.per_bond() ? m.field.bond_stiffness[k] : m.field.stiffness;
      const double s0 = m.field.bond_critical_stretch.empty() ? m.field.critical_stretch
                                                              : m.field.bond_critical_stretch[k];
      energy += (reverse ? 0.5 : 1.0) * 0.5 * stiffness * m.particles.volume[i] * s0 * s0 /
                f.inverse_length[k];
    }
  }
  return energy / p.area / g0;
}

struct Specimen {
  std::string name;
  int dim;
  std::string plane_mode; // 2D only
  double jitter;
  bool clamp;
};

std::string scene_text(const Specimen& s, const std::string& surface, const std::string& volume,
                       double extent) {
  const double e = extent * lambda, c = 4 * lambda;
  std::string t = "dimension: " + std::to_string(s.dim) + "\n";
  if (s.dim == 2) {
    t += "plane: " + s.plane_mode + "\nthickness: " + std::to_string(thickness) + "\n";
  }
  if (s.dim == 1) {
    t += "cross_section: " + std::to_string(section) + "\n";
  }
  t += "lattice:\n  spacing: " + std::to_string(lambda) + "\n";
  if (s.jitter > 0) {
    t += "  position_jitter: " + std::to_string(s.jitter) + "\n";
  }
  t += "materials:\n  glass:\n    youngs_modulus: 72e9\n    density: 2500\n"
       "    fracture_energy: 10\n";
  auto box = [&](double x0, double x1) {
    std::ostringstream o;
    o << "[[" << x0;
    for (int a = 1; a < s.dim; ++a) {
      o << ", 0";
    }
    o << "], [" << x1;
    for (int a = 1; a < s.dim; ++a) {
      o << ", " << e;
    }
    o << "]]";
    return o.str();
  };
  t += "bodies:\n  - name: block\n    material: glass\n    box: " + box(0, e) + "\n";
  if (s.clamp) {
    t += "  - name: clamp\n    material: glass\n    box: " + box(-c, 0) + "\n";
    t += "supports:\n  - name: clamp\n    box: " + box(-c, 0) + "\n    mirror: {x: 0}\n";
  }
  t += "effects: [damage]\nsolver:\n  end_time: 1\n";
  if (!surface.empty()) {
    t += "model:\n  surface_correction: " + surface + "\n  volume_correction: " + volume + "\n";
  }
  return t;
}

/// The planes of a block of side `extent` spacings (cell-centred: particles at (k + ½)λ).
std::vector<Plane> planes_for(int dim, double extent, bool clamp) {
  const double mid = 0.5 * extent * lambda, w = 4 * lambda;
  const double r = 1 / std::sqrt(2.0);
  const double cross = dim == 3 ? 4 * w * w : dim == 2 ? 2 * w * thickness : section;
  const double h2 = dim == 3 ? w : 0;
  const pd::Vec3 ex{1, 0, 0}, ey{0, 1, 0}, ez{0, 0, 1}, zero{0, 0, 0};
  std::vector<Plane> out;
  auto add = [&](const char* name, pd::Vec3 point, pd::Vec3 n, pd::Vec3 a, double half,
                 double area) {
    if (dim == 1) {
      out.push_back({name, point, n, zero, 0, zero, 0, section});
    } else {
      out.push_back({name, point, n, a, half, ez, dim == 3 ? h2 : 0, area});
    }
  };
  if (clamp) {
    add("x=1λ by clamp", {1 * lambda, mid, mid}, ex, ey, w, cross);
    add("x=2.25λ by clamp", {2.25 * lambda, mid, mid}, ex, ey, w, cross);
    return out;
  }
  add("bulk x mid", {mid, mid, mid}, ex, ey, w, cross);
  add("bulk x off .25", {mid + 0.25 * lambda, mid, mid}, ex, ey, w, cross);
  if (dim == 1) {
    add("end x=1λ", {1 * lambda, 0, 0}, ex, ey, 0, section);
    return out;
  }
  add("bulk y mid", {mid, mid, mid}, ey, ex, w, cross);
  // 45°: the lattice repeats every √2 λ along the plane; the window spans 4 periods.
  const double wd = 4 * std::sqrt(2.0) * lambda;
  // x + y = (k + ½)λ runs midway between the diagonal rows of particles (x + y = kλ).
  add("bulk 45°", {mid + 0.25 * lambda, mid + 0.25 * lambda, mid}, {r, r, 0}, {r, -r, 0}, wd / 2,
      dim == 3 ? wd * 2 * w : wd * thickness);
  add("bulk 45° off", {mid + 0.3 * lambda, mid, mid}, {r, r, 0}, {r, -r, 0}, wd / 2,
      dim == 3 ? wd * 2 * w : wd * thickness);
  add("along surface y=1λ", {mid, 1 * lambda, mid}, ey, ex, w, cross);
  add("along surface y=2λ", {mid, 2 * lambda, mid}, ey, ex, w, cross);
  add("along surface y=3.25λ", {mid, 3.25 * lambda, mid}, ey, ex, w, cross);
  // Across the free surfaces: the whole plane, over the body's whole section.
  const double section_area =
      dim == 3 ? extent * extent * lambda * lambda : extent * lambda * thickness;
  add("across surface x mid", {mid, mid, mid}, ex, ey, 0, section_area);
  out.back().half2 = 0;
  return out;
}

struct Row {
  std::string setup, pair, plane;
  std::optional<double> ratio; ///< empty: the scene reader refused the pair
};

std::vector<Row> measure(const Specimen& s, const std::string& surface, const std::string& volume) {
  const double extent = s.dim == 3 ? 16 : s.dim == 1 ? 40 : 24;
  std::vector<Row> rows;
  const std::string pair = surface.empty() ? "defaults" : surface + "+" + volume;
  try {
    const pd::Scene scene = pd::parse_scene(scene_text(s, surface, volume, extent), "i.yaml");
    const pd::Model m = pd::build_model(scene);
    const auto& s0s = m.field.bond_critical_stretch;
    if (!s0s.empty()) {
      const auto [lo, hi] = std::minmax_element(s0s.begin(), s0s.end());
      std::printf("%-18s %-22s s0 from %.4g to %.4g, %zu directed bonds\n", s.name.c_str(),
                  pair.c_str(), *lo, *hi, s0s.size());
    } else {
      std::printf("%-18s %-22s s0 %.4g uniform\n", s.name.c_str(), pair.c_str(),
                  m.field.critical_stretch);
    }
    for (const Plane& p : planes_for(s.dim, extent, s.clamp)) {
      rows.push_back({s.name, pair, p.name, crossing_ratio(m, p)});
    }
  } catch (const std::exception& e) {
    rows.push_back({s.name, pair, std::string("refused: ") + e.what(), std::nullopt});
  }
  return rows;
}

const std::vector<Specimen> setups = {
    {"1D", 1, "", 0, false},
    {"2D stress", 2, "stress", 0, false},
    {"2D strain", 2, "strain", 0, false},
    {"2D stress clamp", 2, "stress", 0, true},
    {"2D stress jitter", 2, "stress", 0.2, false},
    {"3D", 3, "", 0, false},
};

const std::vector<std::string> surfaces = {"none",          "volume", "energy",
                                           "macek-silling", "tensor", "ghost"};
const std::vector<std::string> volumes = {"none", "linear", "exact", "moment", "gradient"};

// Prints E_cross / (G0 A) for every setup, plane and correction pair; gates nothing.
TEST(FractureEnergyInvariant, Measure) {
  for (const Specimen& s : setups) {
    std::vector<std::pair<std::string, std::string>> pairs = {{"", ""}};
    for (const auto& a : surfaces) {
      for (const auto& b : volumes) {
        pairs.emplace_back(a, b);
      }
    }
    for (const auto& [a, b] : pairs) {
      for (const Row& r : measure(s, a, b)) {
        if (r.ratio) {
          std::printf("%-18s %-22s %-24s %8.4f  (%+6.1f %%)\n", r.setup.c_str(), r.pair.c_str(),
                      r.plane.c_str(), *r.ratio, 100 * (*r.ratio - 1));
        } else {
          std::printf("%-18s %-22s %s\n", r.setup.c_str(), r.pair.c_str(),
                      r.plane.substr(0, 100).c_str());
        }
      }
    }
  }
}

} // namespace

namespace {

double ratio_at(const std::vector<Row>& rows, const std::string& plane) {
  for (const Row& r : rows) {
    if (r.plane == plane && r.ratio) {
      return *r.ratio;
    }
  }
  ADD_FAILURE() << "no plane " << plane;
  return 0;
}

const Specimen& specimen(const std::string& name) {
  for (const Specimen& s : setups) {
    if (s.name == name) {
      return s;
    }
  }
  throw std::invalid_argument(name);
}

// What holds today on a lattice with the defaults: the cost of a plane does not depend on where
// between the rows of particles it lies, the ghost layer and the clamp image give a plane by a
// surface or a clamp the bulk's cost, and in 1D the `gradient` scaling of s0 gives a lattice
// plane normal to the axis the cost of the uncorrected lattice (what
// fracture_energy_weight_ratio promises). In 2D and 3D each treatment's s0 is divided by its own
// lattice toughness ratio instead (model.hpp), so there the treatments' costs differ by design.
// What does not hold is the level itself (DISABLED_ test below).
TEST(FractureEnergyInvariant, DefaultsOnALatticeDoNotDependOnPlaceOrSurface) {
  for (const char* name : {"1D", "2D stress", "2D strain", "3D"}) {
    SCOPED_TRACE(name);
    const Specimen& s = specimen(name);
    const auto rows = measure(s, "", "");
    const double bulk = ratio_at(rows, "bulk x mid");
    EXPECT_NEAR(ratio_at(rows, "bulk x off .25"), bulk, 1e-9 * bulk);
    if (s.dim == 1) {
      EXPECT_NEAR(ratio_at(measure(s, "none", "none"), "bulk x mid"), bulk, 1e-9 * bulk);
    }
    if (s.dim == 1) {
      continue;
    }
    EXPECT_NEAR(ratio_at(rows, "bulk y mid"), bulk, 1e-9 * bulk);
    EXPECT_NEAR(ratio_at(rows, "bulk 45° off"), ratio_at(rows, "bulk 45°"), 1e-9 * bulk);
    for (const char* plane :
         {"along surface y=2λ", "along surface y=3.25λ", "across surface x mid"}) {
      EXPECT_NEAR(ratio_at(rows, plane), bulk, 1e-6 * bulk) << plane;
    }
  }
  const auto clamp = measure(specimen("2D stress clamp"), "", "");
  const double bulk = ratio_at(measure(specimen("2D stress"), "", ""), "bulk x mid");
  EXPECT_NEAR(ratio_at(clamp, "x=2.25λ by clamp"), bulk, 1e-6 * bulk);
}

// The target of issue 36: every plane, every specimen, every documented pair costs G0 within
// 1 %. Fails today on most rows (the Measure table). In the bulk of the 2D default lattice
// (m = 2√3) the bonds crossing a plane hold 0.387 G0 at their s0: 0.504 G0 at the energy-derived
// s0 of eq. 11, because the `gradient` weights move the stiffness onto the bonds up to 2λ, which
// cross a plane less often than the horizon's (without weights the lattice sum is 0.929 G0, short
// of eq. 11's integral), and s0 is then divided by the lattice toughness ratio 1.141 (the
// discrete crack needs 1.141² × the energy its crossing bonds hold: lattice_toughness.cpp).
// Planes within one spacing of a surface or a clamp cost less again; a 45° plane differs from an
// axis plane by 1–3 %. With brittle bonds the invariant and a crack that runs at G0 cannot both
// hold.
TEST(FractureEnergyInvariant, DISABLED_EveryPlaneCostsG0WithinOnePercent) {
  for (const Specimen& s : setups) {
    std::vector<std::pair<std::string, std::string>> pairs = {{"", ""}};
    for (const auto& a : surfaces) {
      for (const auto& b : volumes) {
        pairs.emplace_back(a, b);
      }
    }
    for (const auto& [a, b] : pairs) {
      for (const Row& r : measure(s, a, b)) {
        if (r.ratio) {
          EXPECT_NEAR(*r.ratio, 1.0, 0.01) << r.setup << " " << r.pair << " " << r.plane;
        }
      }
    }
  }
}

} // namespace
