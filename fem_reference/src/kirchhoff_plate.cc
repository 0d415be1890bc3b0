#include "kirchhoff_plate.h"

#include <deal.II/base/polynomial.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/lac/lapack_full_matrix.h>
#include <deal.II/lac/vector.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace pdfem
{
  namespace
  {
    unsigned int exponent(const EdgeCondition c)
    {
      switch (c)
        {
          case EdgeCondition::clamped:
            return 2;
          case EdgeCondition::simply_supported:
            return 1;
          case EdgeCondition::free:
            return 0;
        }
      return 0;
    }

    // The 1D basis X_m(xi) = B(xi) L_m(xi) on [0, 1] with the bubble
    // B(xi) = xi^k0 (1 - xi)^k1 and the Legendre polynomial
    // L_m(xi) = P_m(2 xi - 1).  P_m and its derivatives come from the
    // three-term recurrences
    //   (m+1) P_{m+1} = (2m+1) s P_m - m P_{m-1},
    //   P'_{m+1}  = P'_{m-1}  + (2m+1) P_m,
    //   P''_{m+1} = P''_{m-1} + (2m+1) P'_m,
    // which stay accurate for high degrees (a monomial representation does
    // not: its coefficients grow like 2^(2m) and cancel).
    class Basis1D
    {
    public:
      Basis1D(const unsigned int n_, const EdgeCondition c0,
              const EdgeCondition c1)
        : n(n_)
        , bubble(std::vector<double>{1.})
      {
        for (unsigned int k = 0; k < exponent(c0); ++k)
          bubble *= dealii::Polynomials::Polynomial<double>(
            std::vector<double>{0., 1.});
        for (unsigned int k = 0; k < exponent(c1); ++k)
          bubble *= dealii::Polynomials::Polynomial<double>(
            std::vector<double>{1., -1.});
      }

      // values[m][r] = d^r X_m / d xi^r (xi), r = 0, 1, 2
      void evaluate(const double xi,
                    std::vector<std::array<double, 3>> &values) const
      {
        values.resize(n);
        std::vector<double> b(3);
        bubble.value(xi, b);
        const double s = 2. * xi - 1.;
        // P_m, dP_m/ds, d2P_m/ds2 for m-1 (a) and m (c)
        std::array<double, 3> pm1{0., 0., 0.}, p{1., 0., 0.};
        for (unsigned int m = 0; m < n; ++m)
          {
            // derivatives with respect to xi: d/dxi = 2 d/ds
            const double L = p[0], dL = 2. * p[1], ddL = 4. * p[2];
            values[m][0] = b[0] * L;
            values[m][1] = b[1] * L + b[0] * dL;
            values[m][2] = b[2] * L + 2. * b[1] * dL + b[0] * ddL;
            const double          k = static_cast<double>(m);
            std::array<double, 3> next;
            next[0] = ((2. * k + 1.) * s * p[0] - k * pm1[0]) / (k + 1.);
            next[1] = pm1[1] + (2. * k + 1.) * p[0];
            next[2] = pm1[2] + (2. * k + 1.) * p[1];
            if (m == 0)
              next = {s, 1., 0.};
            pm1 = p;
            p   = next;
          }
      }

      unsigned int size() const
      {
        return n;
      }

    private:
      unsigned int                            n;
      dealii::Polynomials::Polynomial<double> bubble;
    };

    // M[r][s](m,k) = ∫_0^len X_m^(r)(x) X_k^(s)(x) dx for r,s = 0..2,
    // and the integrals ∫_0^len X_m dx.
    struct Matrices1D
    {
      std::vector<std::vector<double>> M[3][3];
      std::vector<double>              integral;
    };

    Matrices1D matrices_1d(const Basis1D &basis, const double len)
    {
      const unsigned int      n = basis.size();
      const dealii::QGauss<1> quad(n + 6);
      const unsigned int      nq = quad.size();
      // values[q][m][r] = d^r X_m / dx^r at the quadrature point q
      std::vector<std::vector<std::array<double, 3>>> values(nq);
      for (unsigned int q = 0; q < nq; ++q)
        {
          basis.evaluate(quad.point(q)[0], values[q]);
          for (unsigned int m = 0; m < n; ++m)
            for (unsigned int r = 0; r < 3; ++r)
              values[q][m][r] /= std::pow(len, static_cast<double>(r));
        }
      Matrices1D result;
      for (auto &row : result.M)
        for (auto &mat : row)
          mat.assign(n, std::vector<double>(n, 0.));
      result.integral.assign(n, 0.);
      for (unsigned int q = 0; q < nq; ++q)
        {
          const double w = quad.weight(q) * len;
          for (unsigned int m = 0; m < n; ++m)
            {
              result.integral[m] += w * values[q][m][0];
              for (unsigned int k = 0; k < n; ++k)
                for (unsigned int r = 0; r < 3; ++r)
                  for (unsigned int s = 0; s < 3; ++s)
                    result.M[r][s][m][k] +=
                      w * values[q][m][r] * values[q][k][s];
            }
        }
      return result;
    }
  } // namespace

  std::string to_string(const EdgeCondition c)
  {
    switch (c)
      {
        case EdgeCondition::clamped:
          return "clamped";
        case EdgeCondition::simply_supported:
          return "simply supported";
        case EdgeCondition::free:
          return "free";
      }
    return "?";
  }

  KirchhoffRitz::KirchhoffRitz(const KirchhoffPlate &p, const unsigned int n_)
    : plate(p)
    , n(n_)
  {
    const auto X = matrices_1d(Basis1D(n, plate.x0, plate.x1), plate.a);
    const auto Y = matrices_1d(Basis1D(n, plate.y0, plate.y1), plate.b);

    // Stiffness K_{(m,n),(k,l)} = D ∫∫ [ w_xx w'_xx + w_yy w'_yy
    //   + nu (w_xx w'_yy + w_yy w'_xx) + 2 (1 - nu) w_xy w'_xy ],
    // which separates into products of the 1D matrices.
    const unsigned int           N = n * n;
    dealii::LAPACKFullMatrix<double> K(N, N);
    dealii::Vector<double>           F(N);
    const double                     D = plate.D, nu = plate.nu;
    for (unsigned int m = 0; m < n; ++m)
      for (unsigned int j = 0; j < n; ++j)
        {
          const unsigned int I = m * n + j;
          F(I)                 = plate.q * X.integral[m] * Y.integral[j];
          for (unsigned int k = 0; k < n; ++k)
            for (unsigned int l = 0; l < n; ++l)
              {
                const unsigned int J = k * n + l;
                K(I, J) =
                  D * (X.M[2][2][m][k] * Y.M[0][0][j][l] +
                       X.M[0][0][m][k] * Y.M[2][2][j][l] +
                       nu * (X.M[2][0][m][k] * Y.M[0][2][j][l] +
                             X.M[0][2][m][k] * Y.M[2][0][j][l]) +
                       2. * (1. - nu) * X.M[1][1][m][k] * Y.M[1][1][j][l]);
              }
        }
    K.compute_lu_factorization();
    K.solve(F);
    coefficients.assign(F.begin(), F.end());
  }

  double KirchhoffRitz::deflection(const double x, const double y) const
  {
    std::vector<std::array<double, 3>> X, Y;
    Basis1D(n, plate.x0, plate.x1).evaluate(x / plate.a, X);
    Basis1D(n, plate.y0, plate.y1).evaluate(y / plate.b, Y);
    double w = 0.;
    for (unsigned int m = 0; m < n; ++m)
      for (unsigned int j = 0; j < n; ++j)
        w += coefficients[m * n + j] * X[m][0] * Y[j][0];
    return w;
  }

  bool kirchhoff_selftest()
  {
    struct Case
    {
      std::string    name;
      KirchhoffPlate plate;
      double         x, y, expected, tolerance;
    };
    using E = EdgeCondition;
    std::vector<Case> cases;
    {
      KirchhoffPlate p;
      p.nu = 0.3;
      cases.push_back({"clamped square plate, centre (Taylor & Govindjee 2004)",
                       p, 0.5, 0.5, 0.00126532, 2e-5});
    }
    {
      KirchhoffPlate p;
      p.nu = 0.3;
      p.x0 = p.x1 = p.y0 = p.y1 = E::simply_supported;
      cases.push_back({"simply supported square plate, centre (Navier series)",
                       p, 0.5, 0.5, 0.00406235, 2e-5});
    }
    {
      KirchhoffPlate p;
      p.nu = 0.;
      p.b  = 0.7;
      p.x0 = E::clamped;
      p.x1 = p.y0 = p.y1 = E::free;
      cases.push_back({"plate clamped at x=0, free elsewhere, nu=0: q a^4/(8D)",
                       p, 1.0, 0.2, 0.125, 1e-10});
    }
    bool ok = true;
    for (const auto &c : cases)
      {
        const KirchhoffRitz ritz(c.plate, 16);
        const double        w   = ritz.deflection(c.x, c.y);
        const double        rel = std::abs(w - c.expected) / c.expected;
        const bool          pass = rel <= c.tolerance;
        ok                       = ok && pass;
        std::printf("%-62s w = %.8g, expected %.8g, rel. diff %.2e (tol %.0e) %s\n",
                    c.name.c_str(), w, c.expected, rel, c.tolerance,
                    pass ? "PASS" : "FAIL");
      }
    return ok;
  }
} // namespace pdfem
