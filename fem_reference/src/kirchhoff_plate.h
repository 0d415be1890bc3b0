// Kirchhoff (thin) plate reference for rectangular plates with any mix of
// clamped / simply supported / free edges under a uniform pressure q, solved
// by the Rayleigh-Ritz method with a tensor-product polynomial basis.
//
// Minimise the total potential energy of the plate (strain energy of the
// bent plate and the energy (Ritz) method as in Timoshenko &
// Woinowsky-Krieger, "Theory of Plates and Shells", 2nd ed., 1959):
//
//   Pi[w] = D/2 ∫∫ [ (w_xx + w_yy)^2 - 2(1-nu)(w_xx w_yy - w_xy^2) ] dx dy
//           - ∫∫ q w dx dy,                     D = E t^3 / (12 (1 - nu^2)),
//
// over w(x,y) = sum_{m,n<N} c_mn X_m(x) Y_n(y) with
//   X_m(x) = xi^k0 (1-xi)^k1 L_m(xi),  xi = x/a,  L_m Legendre on [0,1],
// where k = 2 on a clamped edge (w = w_n = 0), 1 on a simply supported edge
// (w = 0; M_n = 0 is natural) and 0 on a free edge (M_n = V_n = 0 and the
// corner conditions are all natural conditions of Pi).  Because the essential
// conditions are built into the basis and the natural ones come out of the
// minimisation, the Ritz sequence converges to the exact Kirchhoff solution
// as N grows (algebraically near clamped-free corners, where the Kirchhoff
// solution is weakly singular).  Cf. Leissa's Ritz treatments of plates with
// free edges (A.W. Leissa, "The free vibration of rectangular plates",
// J. Sound Vib. 31 (1973) 257-293) that use the same idea.
//
// The Ritz solver is verified by `pd-fem --kirchhoff-selftest` against
//  * the clamped square plate, w_c = 0.00126532 q a^4/D (TWK's table for
//    plates with built-in edges gives 0.00126; the 6-digit value is from
//    Taylor & Govindjee, Commun. Numer. Meth. Engng 20 (2004) 757-765),
//  * the simply supported square plate (Navier series), w_c = 0.00406235 q a^4/D,
//  * a plate clamped along x=0 and free elsewhere with nu = 0, which is exactly
//    a cantilever: w(a, y) = q a^4 / (8 D).
#pragma once

#include <string>
#include <vector>

namespace pdfem
{
  enum class EdgeCondition
  {
    clamped,
    simply_supported,
    free
  };

  struct KirchhoffPlate
  {
    double a  = 1.; // extent in x
    double b  = 1.; // extent in y
    double D  = 1.; // flexural rigidity E t^3 / (12 (1 - nu^2))
    double nu = 0.3;
    double q  = 1.; // uniform pressure, positive in the direction of w
    // edges x = 0, x = a, y = 0, y = b
    EdgeCondition x0 = EdgeCondition::clamped, x1 = EdgeCondition::clamped,
                  y0 = EdgeCondition::clamped, y1 = EdgeCondition::clamped;
  };

  class KirchhoffRitz
  {
  public:
    // n_terms: number of polynomials per direction (N above).
    KirchhoffRitz(const KirchhoffPlate &plate, unsigned int n_terms);

    // Deflection w(x, y) in the direction of the load q.
    double deflection(double x, double y) const;

    unsigned int n_terms() const
    {
      return n;
    }

  private:
    KirchhoffPlate      plate;
    unsigned int        n;
    std::vector<double> coefficients; // c_{m n} at index m*n + n
  };

  // Runs the three verification cases listed above; returns true if all pass
  // and prints a line per case to stdout.
  bool kirchhoff_selftest();

  std::string to_string(EdgeCondition c);
} // namespace pdfem
