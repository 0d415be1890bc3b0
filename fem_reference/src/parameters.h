// The parameters of pd-fem: what a .prm file can set, how it is checked, and the quantities derived
// from it (Lamé constants, beam section, traction). See pd_fem.cc for the problem statement.
#pragma once

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>
#include <string>
#include <vector>

namespace pdfem {
using namespace dealii;

// Everything a .prm file can set.  declare() documents every entry;
// `pd-fem --print-parameters` prints them with their documentation.
struct Parameters {
  // Problem
  std::string name;
  std::string theory; // "clamped-clamped beam" | "cantilever beam" |
                      // "kirchhoff plate" | "none"
  // Geometry.  3D: the body is [0,length_x] x [0,width_y] x [0,thickness_z].
  // 2D: [0,length_x] x [0,height_y], of out-of-plane thickness `thickness`.
  unsigned int dimension = 3;
  std::string plane; // 2D: "stress" | "strain"; empty in 3D
  double length_x = 0., width_y = 0., thickness_z = 0.;
  double height_y = 0., thickness = 0.;
  // Material
  double youngs_modulus = 0., poisson_ratio = 0.;
  // Load on the top face (z = thickness_z in 3D, y = height_y in 2D), pointing down
  std::string load_kind; // "line load" | "pressure"
  double load_magnitude = 0.;
  // Boundary conditions: boundary ids (0..5 = x-,x+,y-,y+,z-,z+) clamped
  std::vector<unsigned int> clamped_faces;
  // Discretisation
  unsigned int degree = 2;
  double base_element_size = 0.;
  unsigned int n_levels = 3, n_coarse_levels = 3;
  // Level k has base subdivisions x level_multipliers[k] cells per direction; empty: 2^k (each
  // level halves every cell edge).
  std::vector<unsigned int> level_multipliers;
  // Mesh grading toward these faces (ids as clamped_faces): within `graded_layer` (a fraction of
  // the extent) of such a face the cell edges grow like distance^(1 - 1/grading_exponent).
  std::vector<unsigned int> graded_faces;
  double grading_exponent = 1., graded_layer = 0.25;
  // The multiplier of level k: level_multipliers[k], or 2^k.
  unsigned int level_multiplier(unsigned int level) const;
  // Solver
  std::string preconditioner; // "AMG" | "SSOR"
  double relative_tolerance = 1e-10;
  unsigned int max_iterations = 10000;
  // Output.  Points have `dimension` coordinates; the rest of the Point<3> is 0.
  struct NamedPoint {
    std::string name;
    Point<3> point;
  };
  struct SampleLine {
    std::string name;
    Point<3> start, end;
    unsigned int n_points = 2;
  };
  std::vector<NamedPoint> quantities;
  std::vector<SampleLine> lines;
  bool write_vtu = true;

  // Extent of the body along each of its `dimension` axes.
  std::vector<double> extent() const;
  // Width b of a beam's section: Width y in 3D, the out-of-plane Thickness in 2D.
  double section_width() const;
  // Depth h of a beam's section, along the load: Thickness z in 3D, Height y in 2D.
  double section_depth() const;
  // Traction magnitude on the top face (N/m^2): p/b for a line load p.
  double traction() const;
  // Load per unit length of span (N/m): q*b for a pressure q.
  double line_load() const;
  // Lamé constants of the constitutive law the FE model solves: those of (E, nu) in 3D and in
  // plane strain (eps_zz = 0); in plane stress (sigma_zz = 0) lambda* = 2 lambda mu/(lambda + 2
  // mu).
  double lame_lambda() const;
  double lame_mu() const;
  // Modulus of a beam's bending fibres: E, but E/(1 - nu^2) in plane strain, where eps_zz = 0
  // stiffens them.
  double bending_modulus() const;
  // "3D", "2D plane stress" or "2D plane strain": names the model in summaries and notes.
  std::string model_name() const;

  static void declare(ParameterHandler& prm);
  // Reads and checks the entries; throws with the offending entry named if they contradict each
  // other (an entry of the other dimension, a point with the wrong number of coordinates, ...).
  void parse(ParameterHandler& prm);
};
} // namespace pdfem
