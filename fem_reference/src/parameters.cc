#include "parameters.h"

#include "elastic_common.h"

#include <algorithm>
#include <cmath>
#include <deal.II/base/utilities.h>
#include <set>
#include <stdexcept>

namespace pdfem {
namespace {
const char* const face_names = "x-|x+|y-|y+|z-|z+";

unsigned int face_id(const std::string& name) {
  const std::vector<std::string> names{"x-", "x+", "y-", "y+", "z-", "z+"};
  for (unsigned int i = 0; i < names.size(); ++i)
    if (names[i] == name)
      return i;
  throw std::runtime_error("unknown face '" + name + "'");
}

Point<3> parse_point(const std::vector<double>& v, const std::size_t first,
                     const unsigned int dim) {
  Point<3> p;
  for (unsigned int d = 0; d < dim; ++d)
    p[d] = v.at(first + d);
  return p;
}

// ParameterHandler keeps its entries under mangled names ("Height y" -> "Height_20y"): every
// character other than a letter or digit becomes '_' and two hex digits.
std::string demangle(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s[i] == '_' && i + 2 < s.size()) {
      out += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else
      out += s[i];
  return out;
}

// The entries of one dimension only.  ParameterHandler cannot tell a default from a value the
// file gave except for entries declared mandatory (has_to_be_set): get_entries_wrongly_not_set()
// lists the ones the file left out.  So these are declared mandatory, never asserted as such,
// and an entry of the other dimension that the file does set is an error instead of being
// silently ignored.
struct DimensionEntry {
  const char* subsection;
  const char* entry;
  unsigned int dimension;
};
const DimensionEntry dimension_entries[] = {{"Geometry", "Width y", 3},
                                            {"Geometry", "Thickness z", 3},
                                            {"Geometry", "Plane", 2},
                                            {"Geometry", "Height y", 2},
                                            {"Geometry", "Thickness", 2}};

std::set<std::string> entries_given(const ParameterHandler& p) {
  std::set<std::string> not_given;
  for (const std::string& key : p.get_entries_wrongly_not_set())
    not_given.insert(demangle(key));
  std::set<std::string> given;
  for (const DimensionEntry& e : dimension_entries) {
    const std::string path = std::string(e.subsection) + "." + e.entry;
    if (not_given.count(path) == 0)
      given.insert(path);
  }
  return given;
}

void check_dimension_entries(const ParameterHandler& p, const unsigned int dim) {
  const std::set<std::string> given = entries_given(p);
  for (const DimensionEntry& e : dimension_entries) {
    const std::string path = std::string(e.subsection) + "." + e.entry;
    if (e.dimension != dim && given.count(path))
      throw std::runtime_error(
          std::string(e.subsection) + "/" + e.entry +
          " applies to Dimension = " + std::to_string(e.dimension) +
          " only, but the file has Dimension = " + std::to_string(dim) +
          (dim == 2 ? " (in 2D the body is Length x by Height y, of out-of-plane Thickness)"
                    : " (in 3D the body is Length x by Width y by Thickness z)"));
  }
  if (dim == 2)
    for (const char* entry : {"Plane", "Height y", "Thickness"})
      if (!given.count(std::string("Geometry.") + entry))
        throw std::runtime_error(std::string("Dimension = 2 needs Geometry/") + entry +
                                 " (the body is Length x by Height y, of out-of-plane "
                                 "Thickness, in plane stress or plane strain)");
}

// Why: a point or line written for the other dimension would otherwise be read with a coordinate
// dropped or invented.
void check_coordinates(const std::string& entry, const std::string& name, const std::size_t given,
                       const std::size_t expected, const unsigned int dim,
                       const char* expected_form) {
  if (given != expected)
    throw std::runtime_error("Output/" + entry + ": '" + name + "' has " + std::to_string(given) +
                             " numbers, but Dimension = " + std::to_string(dim) + " needs " +
                             std::to_string(expected) + " (" + expected_form + ")");
}

void declare_problem_and_geometry(ParameterHandler& prm) {
  prm.enter_subsection("Problem");
  prm.declare_entry("Name", "problem", Patterns::Anything(),
                    "Short name of the problem; names the default output "
                    "directory fem_reference/out/NAME and the summary.");
  prm.declare_entry(
      "Theory", "none",
      Patterns::Selection("clamped-clamped beam|cantilever beam|kirchhoff plate|none"),
      "Classical solution printed beside the FE result: Euler-Bernoulli "
      "and Timoshenko beam theory with span Length x, section width Width y (2D: Thickness) and "
      "depth Thickness z (2D: Height y), bending modulus E (plane strain: E/(1-nu^2)) "
      "(clamped-clamped: midspan; cantilever: tip), or (3D only) a "
      "Kirchhoff plate with the clamped faces x-, x+, y-, y+ as built-in "
      "edges and all other edges free (Rayleigh-Ritz series solution).");
  prm.leave_subsection();

  prm.enter_subsection("Geometry");
  prm.declare_entry("Dimension", "3", Patterns::Integer(2, 3),
                    "Spatial dimension of the model. 3: the body is [0,Length x] x "
                    "[0,Width y] x [0,Thickness z], loaded on its top face z = Thickness z "
                    "in -z. 2: the body is the rectangle [0,Length x] x [0,Height y] of "
                    "out-of-plane thickness Thickness, in plane stress or plane strain "
                    "(Plane), loaded on its top edge y = Height y in -y. Entries of the "
                    "other dimension are errors.");
  prm.declare_entry("Plane", "stress", Patterns::Selection("stress|strain"),
                    "2D only, required there. stress: sigma_zz = 0 (a thin slab loaded in "
                    "its plane), the 2D equations with E, nu and the plane-stress law "
                    "lambda* = 2 lambda mu/(lambda + 2 mu) = E nu/(1 - nu^2). strain: "
                    "eps_zz = 0 (a long body), the 2D Lame equations with the 3D lambda, mu "
                    "of E, nu.",
                    true);
  prm.declare_entry("Length x", "3.5", Patterns::Double(0., 1e6),
                    "Extent of the body in x (span of a beam), in m.");
  prm.declare_entry("Width y", "0.3", Patterns::Double(0., 1e6),
                    "3D only. Extent of the body in y (width b of a beam section), in m.", true);
  prm.declare_entry("Thickness z", "0.4", Patterns::Double(0., 1e6),
                    "3D only. Extent of the body in z (depth h of a beam section, "
                    "thickness t of a plate), in m.",
                    true);
  prm.declare_entry("Height y", "0.4", Patterns::Double(0., 1e6),
                    "2D only, required there. Extent of the body in y (depth h of a beam), "
                    "in m.",
                    true);
  prm.declare_entry("Thickness", "0.3", Patterns::Double(0., 1e6),
                    "2D only, required there. Out-of-plane thickness t (width b of a beam's "
                    "section), in m. The 2D solution is per unit thickness, so t enters only "
                    "where a line load p (N/m) becomes the traction p/t on the top edge.",
                    true);
  prm.leave_subsection();
}

void declare_material_load_supports(ParameterHandler& prm) {
  prm.enter_subsection("Material");
  prm.declare_entry("Young modulus", "20e9", Patterns::Double(0., 1e15),
                    "Young's modulus E of the isotropic linear elastic "
                    "material, in Pa.");
  prm.declare_entry("Poisson ratio", "0.25", Patterns::Double(-0.999, 0.499),
                    "Poisson's ratio nu (-1 < nu < 0.5).");
  prm.leave_subsection();

  prm.enter_subsection("Load");
  prm.declare_entry("Kind", "line load", Patterns::Selection("line load|pressure"),
                    "How Magnitude is to be read. 'line load': a load p "
                    "per unit length of x (N/m), applied as the uniform "
                    "traction p/b on the top face z = Thickness z, b = Width y "
                    "(2D: on the top edge y = Height y, b = Thickness). "
                    "'pressure': a uniform traction q (N/m^2) on the "
                    "top face. The traction always points down (-z; 2D: -y).");
  prm.declare_entry("Magnitude", "1e4", Patterns::Double(0., 1e12),
                    "Magnitude of the load: N/m for a line load, N/m^2 "
                    "for a pressure.");
  prm.leave_subsection();

  prm.enter_subsection("Boundary conditions");
  prm.declare_entry("Clamped faces", "x-, x+",
                    Patterns::List(Patterns::Selection(face_names), 0, 6, ","),
                    "Comma separated list of the faces on which every displacement "
                    "component is zero: x- (x=0), x+ (x=Length x), y- (y=0), y+ "
                    "(y=Width y), z- (z=0), z+ (z=Thickness z). In 2D the faces are the "
                    "edges x-, x+, y-, y+ (y+ is y=Height y); z- and z+ are errors. All "
                    "other faces are traction free except the loaded top face.");
  prm.leave_subsection();
}

void declare_numerics_and_output(ParameterHandler& prm) {
  prm.enter_subsection("Discretisation");
  prm.declare_entry("Finite element degree", "2", Patterns::Integer(1, 6),
                    "Polynomial degree p of the FE_Q^dim displacement "
                    "element. p = 1 locks in bending; use p >= 2.");
  prm.declare_entry("Base element size", "0.4", Patterns::Double(0., 1e6),
                    "Target edge length of the cells of the coarsest "
                    "mesh, in m. The number of subdivisions in each "
                    "direction is max(1, round(extent/size)), so cells "
                    "are nearly cubes (squares in 2D). Each further level halves every "
                    "cell edge (global refinement).");
  prm.declare_entry("Number of levels", "4", Patterns::Integer(1, 8),
                    "Number of meshes of the reference run (level 0 is "
                    "the base mesh). Three or more are needed for the "
                    "Richardson error estimate.");
  prm.declare_entry("Coarse levels", "3", Patterns::Integer(1, 8),
                    "Number of meshes used with --coarse (quick tests).");
  prm.declare_entry("Level multipliers", "", Patterns::List(Patterns::Integer(1, 1000), 0, 20, ","),
                    "Comma separated, increasing: level k has (base subdivisions) x m_k cells "
                    "per direction, so its mesh size is h0/m_k, and Richardson extrapolation "
                    "uses these sizes (the ratios need not be equal). Needs at least as many "
                    "entries as levels are run. Empty: m_k = 2^k, each level halves every "
                    "cell edge.");
  prm.declare_entry("Graded faces", "", Patterns::List(Patterns::Selection(face_names), 0, 6, ","),
                    "Faces (as in Boundary conditions) toward which the mesh is graded: "
                    "within Graded layer of such a face, at distance d, the map of a uniform "
                    "mesh is d ~ s^beta (beta = Grading exponent), so cells shrink toward "
                    "the face and the edge singularities there (clamped face meeting a free "
                    "one: u ~ r^0.7) are resolved at the rate of a smooth solution for "
                    "beta >= p/0.7. Cells stay boxes (one map per axis). Empty: uniform.");
  prm.declare_entry("Grading exponent", "1", Patterns::Double(1., 6.),
                    "beta of Graded faces; 1 is a uniform mesh.");
  prm.declare_entry("Graded layer", "0.25", Patterns::Double(0.01, 0.5),
                    "Width of the graded layer at each graded face, as a fraction of the "
                    "extent of that axis; between the layers the mesh is uniform, its cells "
                    "1/(1 - (number of graded ends) x layer x (1 - 1/beta)) times those of an "
                    "ungraded mesh.");
  prm.leave_subsection();

  prm.enter_subsection("Solver");
  prm.declare_entry("Preconditioner", "AMG", Patterns::Selection("AMG|SSOR"),
                    "Preconditioner of the conjugate gradient solver: "
                    "Trilinos ML smoothed-aggregation AMG with the rigid-body modes "
                    "(six in 3D, three in 2D) as near null space, or SSOR.");
  prm.declare_entry("Relative tolerance", "1e-10", Patterns::Double(0., 1.),
                    "CG stops when |b - A x| <= tolerance * |b|.");
  prm.declare_entry("Maximum iterations", "10000", Patterns::Integer(1),
                    "Maximum number of CG iterations.");
  prm.leave_subsection();

  prm.enter_subsection("Output");
  prm.declare_entry("Quantities of interest", "midspan: 1.75, 0.15, 0.2",
                    Patterns::Map(Patterns::Anything(),
                                  Patterns::List(Patterns::Double(), 2, 3, ","), 1,
                                  Patterns::Map::max_int_value, ";", ":"),
                    "Points at which the deflection, positive downward (-u_z; 2D: -u_y), "
                    "is reported per level and extrapolated, as 'name: x, y, z' "
                    "(2D: 'name: x, y') entries separated by ';'.");
  prm.declare_entry("Sample lines", "centreline: 0, 0.15, 0.2, 3.5, 0.15, 0.2, 71",
                    Patterns::Map(Patterns::Anything(),
                                  Patterns::List(Patterns::Double(), 5, 7, ","), 0,
                                  Patterns::Map::max_int_value, ";", ":"),
                    "Straight lines along which the finest solution is sampled into "
                    "NAME.csv, as 'name: x0, y0, z0, x1, y1, z1, number of points' "
                    "(2D: 'name: x0, y0, x1, y1, number of points') entries separated by ';'.");
  prm.declare_entry("Write VTU", "true", Patterns::Bool(),
                    "Write solution.vtu (finest level, second order "
                    "Lagrange cells) for ParaView.");
  prm.leave_subsection();
}

void parse_output(ParameterHandler& p, Parameters& prm) {
  const unsigned int dim = prm.dimension;
  p.enter_subsection("Output");
  prm.quantities.clear();
  for (const auto& entry : Utilities::split_string_list(p.get("Quantities of interest"), ';')) {
    const auto kv = Utilities::split_string_list(entry, ':');
    const auto v = Utilities::string_to_double(Utilities::split_string_list(kv.at(1), ','));
    check_coordinates("Quantities of interest", kv.at(0), v.size(), dim, dim,
                      dim == 2 ? "x, y" : "x, y, z");
    prm.quantities.push_back({kv.at(0), parse_point(v, 0, dim)});
  }
  prm.lines.clear();
  for (const auto& entry : Utilities::split_string_list(p.get("Sample lines"), ';')) {
    const auto kv = Utilities::split_string_list(entry, ':');
    const auto v = Utilities::string_to_double(Utilities::split_string_list(kv.at(1), ','));
    check_coordinates("Sample lines", kv.at(0), v.size(), 2 * dim + 1, dim,
                      dim == 2 ? "x0, y0, x1, y1, number of points"
                               : "x0, y0, z0, x1, y1, z1, number of points");
    if (v.back() < 2.)
      throw std::runtime_error("sample line '" + kv.at(0) + "' needs at least 2 points");
    prm.lines.push_back({kv.at(0), parse_point(v, 0, dim), parse_point(v, dim, dim),
                         static_cast<unsigned int>(std::lround(v.back()))});
  }
  prm.write_vtu = p.get_bool("Write VTU");
  p.leave_subsection();
}
} // namespace

unsigned int Parameters::level_multiplier(const unsigned int level) const {
  if (level_multipliers.empty())
    return 1U << level;
  if (level >= level_multipliers.size())
    throw std::runtime_error("Discretisation/Level multipliers has " +
                             std::to_string(level_multipliers.size()) + " entries, but level " +
                             std::to_string(level) + " was asked for");
  return level_multipliers[level];
}

std::vector<double> Parameters::extent() const {
  if (dimension == 2)
    return {length_x, height_y};
  return {length_x, width_y, thickness_z};
}

double Parameters::section_width() const {
  return dimension == 2 ? thickness : width_y;
}

double Parameters::section_depth() const {
  return dimension == 2 ? height_y : thickness_z;
}

double Parameters::traction() const {
  return load_kind == "line load" ? load_magnitude / section_width() : load_magnitude;
}

double Parameters::line_load() const {
  return traction() * section_width();
}

double Parameters::lame_lambda() const {
  return lame_constants(youngs_modulus, poisson_ratio, dimension == 2 && plane == "stress").lambda;
}

double Parameters::lame_mu() const {
  return lame_constants(youngs_modulus, poisson_ratio, false).mu;
}

double Parameters::bending_modulus() const {
  const double nu = poisson_ratio;
  return dimension == 2 && plane == "strain" ? youngs_modulus / (1. - nu * nu) : youngs_modulus;
}

std::string Parameters::model_name() const {
  return dimension == 2 ? "2D plane " + plane : "3D";
}

void Parameters::declare(ParameterHandler& prm) {
  declare_problem_and_geometry(prm);
  declare_material_load_supports(prm);
  declare_numerics_and_output(prm);
}

void Parameters::parse(ParameterHandler& p) {
  p.enter_subsection("Problem");
  name = p.get("Name");
  theory = p.get("Theory");
  p.leave_subsection();

  p.enter_subsection("Geometry");
  dimension = static_cast<unsigned int>(p.get_integer("Dimension"));
  length_x = p.get_double("Length x");
  width_y = p.get_double("Width y");
  thickness_z = p.get_double("Thickness z");
  height_y = p.get_double("Height y");
  thickness = p.get_double("Thickness");
  plane = dimension == 2 ? p.get("Plane") : "";
  p.leave_subsection();
  check_dimension_entries(p, dimension);

  p.enter_subsection("Material");
  youngs_modulus = p.get_double("Young modulus");
  poisson_ratio = p.get_double("Poisson ratio");
  p.leave_subsection();

  p.enter_subsection("Load");
  load_kind = p.get("Kind");
  load_magnitude = p.get_double("Magnitude");
  p.leave_subsection();

  p.enter_subsection("Boundary conditions");
  clamped_faces.clear();
  for (const auto& f : Utilities::split_string_list(p.get("Clamped faces"))) {
    clamped_faces.push_back(face_id(f));
    if (clamped_faces.back() >= 2 * dimension)
      throw std::runtime_error("Boundary conditions/Clamped faces: face " + f +
                               " does not exist with Dimension = " + std::to_string(dimension) +
                               " (the faces are x-, x+, y-, y+" +
                               (dimension == 3 ? ", z-, z+)" : ")"));
  }
  p.leave_subsection();

  p.enter_subsection("Discretisation");
  degree = static_cast<unsigned int>(p.get_integer("Finite element degree"));
  base_element_size = p.get_double("Base element size");
  n_levels = static_cast<unsigned int>(p.get_integer("Number of levels"));
  n_coarse_levels = static_cast<unsigned int>(p.get_integer("Coarse levels"));
  level_multipliers.clear();
  for (const auto& m : Utilities::split_string_list(p.get("Level multipliers")))
    level_multipliers.push_back(static_cast<unsigned int>(Utilities::string_to_int(m)));
  for (std::size_t k = 1; k < level_multipliers.size(); ++k)
    if (level_multipliers[k] <= level_multipliers[k - 1])
      throw std::runtime_error("Discretisation/Level multipliers must increase");
  graded_faces.clear();
  for (const auto& f : Utilities::split_string_list(p.get("Graded faces"))) {
    graded_faces.push_back(face_id(f));
    if (graded_faces.back() >= 2 * dimension)
      throw std::runtime_error("Discretisation/Graded faces: face " + f +
                               " does not exist with Dimension = " + std::to_string(dimension));
  }
  grading_exponent = p.get_double("Grading exponent");
  graded_layer = p.get_double("Graded layer");
  p.leave_subsection();

  p.enter_subsection("Solver");
  preconditioner = p.get("Preconditioner");
  relative_tolerance = p.get_double("Relative tolerance");
  max_iterations = static_cast<unsigned int>(p.get_integer("Maximum iterations"));
  p.leave_subsection();

  parse_output(p, *this);

  if (clamped_faces.empty())
    throw std::runtime_error("Boundary conditions/Clamped faces is empty: the body would be free "
                             "to move as a rigid body and the problem singular.");
  if (dimension == 2 && theory == "kirchhoff plate")
    throw std::runtime_error("Problem/Theory = kirchhoff plate needs Dimension = 3 (a plate has "
                             "no 2D model here); use a beam theory or none");
}
} // namespace pdfem
