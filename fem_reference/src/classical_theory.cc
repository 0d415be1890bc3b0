#include "classical_theory.h"

#include "kirchhoff_plate.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace pdfem {
namespace {
std::string fmt(const double v, const int precision = 6) {
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

std::string percent(const double fe, const double ref) {
  std::ostringstream s;
  s << std::showpos << std::fixed << std::setprecision(2) << 100. * (fe - ref) / ref << " %";
  return s.str();
}

// Why the FE beam is stiffer or more flexible than Timoshenko's; `share` is the part of
// Timoshenko's shear term the FE solution shows on top of Euler-Bernoulli.
std::string beam_explanation(const Parameters& prm, const double share) {
  // Timoshenko & Goodier's plane-stress solution holds in plane strain with nu/(1 - nu) for nu.
  const double nu = prm.poisson_ratio;
  const double nu_eff = prm.dimension == 2 && prm.plane == "strain" ? nu / (1. - nu) : nu;
  const std::string poisson_share = fmt(100. * (0.8 + nu_eff / 2.) / (0.8 * (1. + nu_eff)), 3);
  const bool is_3d = prm.dimension == 3;
  std::ostringstream n;
  if (share < 1.) {
    n << "It is stiffer than Timoshenko because (a) the load "
         "acts on the top face: the transverse normal stress it "
         "causes reduces the shear-type deflection through "
         "Poisson's effect (exact plane-stress solution of a "
         "top-loaded simply supported beam, Timoshenko & "
         "Goodier, Theory of Elasticity, 'Bending of a beam by "
         "uniform load': correction "
         "(12/5)(h/L)^2 (4/5 + nu/2) instead of Timoshenko's "
         "(12/5)(h/L)^2 (4/5)(1 + nu) with kappa = 5/6, i.e. "
      << poisson_share << " % of it";
    if (!is_3d && prm.plane == "strain")
      n << ", with nu/(1 - nu) for nu in plane strain";
    n << "), and (b) the fully clamped end face(s) "
         "u = 0 forbid the Poisson contraction/expansion of the "
         "section (and its warping) where the bending stresses "
         "are largest, which beam theory's built-in section "
         "allows: a stiffening near the supports. ";
    if (is_3d)
      n << "Both are "
           "Poisson effects: for the reference beams of "
           "fem_reference/README.md, the same 3D runs with nu = 0 "
           "agree with Timoshenko to 0.1 % or better. The local 3D "
           "flexibility next to the clamped edges (stress "
           "singularity) acts the other way but is small.";
    else
      n << "The local flexibility next to the clamped edge(s) (stress singularity at the corners "
           "of a clamped edge) acts the other way.";
  } else {
    n << "It is more flexible than Timoshenko: the material "
         "next to the clamped faces deforms locally ("
      << (is_3d ? "3D stress concentration at the built-in edges"
                : "stress singularity at the corners of the clamped edge")
      << ", root "
         "flexibility), which beam theory's rigid built-in "
         "section ignores; this outweighs the stiffening by the "
         "restrained warping and Poisson contraction at the "
         "clamped faces";
    if (!is_3d)
      n << " and by the top load's Poisson effect (Timoshenko & Goodier's exact plane-stress "
           "solution of a top-loaded beam has "
        << poisson_share << " % of Timoshenko's shear term"
        << (prm.plane == "strain" ? ", with nu/(1 - nu) for nu in plane strain" : "") << ")";
    n << ".";
  }
  return n.str();
}

// Euler-Bernoulli and Timoshenko beam theory (e.g. Timoshenko & Gere, Mechanics of Materials;
// shear coefficient 5/6 for a rectangle), E the bending modulus of the model:
//   clamped-clamped, midspan:  p L^4/(384 E I) + p L^2/(8 kappa G A)
//   cantilever, tip:           p L^4/(8 E I)   + p L^2/(2 kappa G A)
void beam_theory(const Parameters& prm, const std::vector<QuantitySummary>& quantities,
                 JsonWriter& w, Theory& th) {
  const double E = prm.bending_modulus(), nu = prm.poisson_ratio, G = prm.lame_mu();
  const double L = prm.length_x, b = prm.section_width(), h = prm.section_depth();
  const double I = b * h * h * h / 12., A = b * h, kappa = 5. / 6.;
  const double p = prm.line_load();
  const bool cc = prm.theory == "clamped-clamped beam";
  const double bending =
      cc ? p * std::pow(L, 4) / (384. * E * I) : p * std::pow(L, 4) / (8. * E * I);
  const double shear = cc ? p * L * L / (8. * kappa * G * A) : p * L * L / (2. * kappa * G * A);
  w.value("kind", prm.theory);
  w.value("model", prm.model_name());
  w.value("location", cc ? "midspan x = L/2" : "tip x = L");
  w.value("formula_euler_bernoulli", cc ? "p L^4 / (384 E I)" : "p L^4 / (8 E I)");
  w.value("formula_timoshenko_shear_part", cc ? "p L^2 / (8 kappa G A)" : "p L^2 / (2 kappa G A)");
  w.value("L", L).value("b", b).value("h", h).value("E", prm.youngs_modulus).value("nu", nu);
  w.value("E_bending", E);
  w.value("E_bending_meaning", prm.dimension == 2 && prm.plane == "strain"
                                   ? "E / (1 - nu^2): plane strain, eps_zz = 0"
                                   : "E");
  w.value("G", G).value("I", I).value("A", A).value("kappa", kappa);
  w.value("p_N_per_m", p);
  w.value("euler_bernoulli", bending);
  w.value("timoshenko", bending + shear);
  if (quantities.empty())
    return;
  const double fe = quantities.front().richardson.extrapolated;
  w.value("fe_quantity", quantities.front().name);
  w.value("fe_extrapolated", fe);
  w.value("fe_vs_euler_bernoulli_rel", (fe - bending) / bending);
  w.value("fe_vs_timoshenko_rel", (fe - bending - shear) / (bending + shear));
  th.values = {{"Euler-Bernoulli", bending}, {"Timoshenko", bending + shear}};
  const double shear_share = (fe - bending) / shear;
  w.value("fe_minus_euler_bernoulli_over_timoshenko_shear_term", shear_share);
  std::ostringstream n;
  n << prm.model_name() << " FE " << quantities.front().name << " deflection " << fmt(fe)
    << " m is " << percent(fe, bending + shear) << " from Timoshenko (" << fmt(bending + shear)
    << " m) and " << percent(fe, bending) << " from Euler-Bernoulli (" << fmt(bending)
    << " m). Euler-Bernoulli omits shear "
    << "deformation; Timoshenko's shear term is " << fmt(100. * shear / (bending + shear), 3)
    << " % of its total (L/h = " << fmt(L / h, 4) << "). The " << prm.model_name()
    << " solution adds " << fmt(100. * shear_share, 3)
    << " % of that shear term to Euler-Bernoulli. " << beam_explanation(prm, shear_share);
  th.notes = n.str();
}

// Kirchhoff plate, Rayleigh-Ritz series (kirchhoff_plate.h).
void plate_theory(const Parameters& prm, const std::vector<QuantitySummary>& quantities,
                  JsonWriter& w, Theory& th) {
  const double E = prm.youngs_modulus, nu = prm.poisson_ratio;
  const double t = prm.thickness_z;
  const double D = E * t * t * t / (12. * (1. - nu * nu));
  KirchhoffPlate plate;
  plate.a = prm.length_x;
  plate.b = prm.width_y;
  plate.D = D;
  plate.nu = nu;
  plate.q = prm.traction();
  auto edge = [&](const unsigned int id) {
    for (const unsigned int c : prm.clamped_faces)
      if (c == id)
        return EdgeCondition::clamped;
    return EdgeCondition::free;
  };
  plate.x0 = edge(0);
  plate.x1 = edge(1);
  plate.y0 = edge(2);
  plate.y1 = edge(3);
  w.value("kind", "Kirchhoff plate, Rayleigh-Ritz series solution");
  w.value("edges", "x=0: " + to_string(plate.x0) + ", x=a: " + to_string(plate.x1) +
                       ", y=0: " + to_string(plate.y0) + ", y=b: " + to_string(plate.y1));
  w.value("a", plate.a).value("b", plate.b).value("t", t);
  w.value("E", E).value("nu", nu).value("D", D).value("q", plate.q);
  const std::vector<unsigned int> terms{8, 12, 16, 20, 24, 28, 32};
  std::vector<KirchhoffRitz> ritz;
  for (const unsigned int N : terms)
    ritz.emplace_back(plate, N);
  w.begin_object("quantities");
  std::ostringstream n;
  for (const auto& q : quantities) {
    w.begin_object(q.name);
    w.begin_array("ritz_sequence");
    for (const auto& r : ritz) {
      w.begin_object();
      w.value("terms_per_direction", r.n_terms());
      w.value("deflection", r.deflection(q.point[0], q.point[1]));
      w.end_object();
    }
    w.end_array();
    const double kirchhoff = ritz.back().deflection(q.point[0], q.point[1]);
    const double previous = ritz[ritz.size() - 2].deflection(q.point[0], q.point[1]);
    w.value("kirchhoff", kirchhoff);
    w.value("kirchhoff_series_rel_change_last_step",
            std::abs(kirchhoff - previous) / std::abs(kirchhoff));
    w.value("coefficient_w_D_over_q_a4", kirchhoff * D / (plate.q * std::pow(plate.a, 4)));
    const double fe = q.richardson.extrapolated;
    w.value("fe_extrapolated", fe);
    w.value("fe_vs_kirchhoff_rel", (fe - kirchhoff) / kirchhoff);
    w.end_object();
    th.values.push_back({"Kirchhoff " + q.name, kirchhoff});
    n << "3D FE " << q.name << " deflection " << fmt(fe) << " m is " << percent(fe, kirchhoff)
      << " from Kirchhoff (" << fmt(kirchhoff) << " m). ";
  }
  w.end_object();
  n << "Kirchhoff (thin plate) theory neglects transverse shear "
       "deformation and treats a clamped edge as w = dw/dn = 0 on "
       "the mid-surface. The plate is moderately thick (t/b = "
    << fmt(t / plate.b, 3) << ", t/a = " << fmt(t / plate.a, 3)
    << "): the 3D solution includes the shear deflection, which "
       "grows like (t/span)^2 relative to bending and is "
       "comparatively large for clamped edges, and the local 3D "
       "flexibility at the clamped faces (stress concentration at "
       "the built-in edges). Both make the 3D plate more flexible "
       "than Kirchhoff; the clamped faces also restrain the Poisson "
       "contraction there (a small stiffening). The difference "
       "shrinks towards zero as t -> 0 (see fem_reference/README.md, "
       "thickness study).";
  th.notes = n.str();
}
} // namespace

Theory classical_theory(const Parameters& prm, const std::vector<QuantitySummary>& quantities) {
  Theory th;
  std::ostringstream js;
  JsonWriter w(js);
  w.begin_object();
  w.value("deflection_sign",
          prm.dimension == 2 ? "positive downward (-u_y), in m" : "positive downward (-u_z), in m");
  if (prm.theory == "clamped-clamped beam" || prm.theory == "cantilever beam")
    beam_theory(prm, quantities, w, th);
  else if (prm.theory == "kirchhoff plate")
    plate_theory(prm, quantities, w, th);
  else
    w.value("kind", "none");
  w.end_object();
  th.json = js.str();
  return th;
}
} // namespace pdfem
