// The classical solutions pd-fem prints beside its FE result: Euler-Bernoulli and Timoshenko beams
// (3D, plane stress, plane strain) and the Kirchhoff plate series (3D).
#pragma once

#include "parameters.h"
#include "report.h"

#include <string>
#include <utility>
#include <vector>

namespace pdfem {
struct QuantitySummary {
  std::string name;
  Point<3> point;                  // coordinates beyond the dimension are 0
  double finest = 0.;              // value on the finest level
  Richardson richardson;           // extrapolation from the last three levels
  std::vector<Richardson> triples; // the same from every three consecutive levels
};

struct Theory {
  std::string json; // the "theory" object of summary.json
  std::string notes;
  // per quantity: classical values to print
  std::vector<std::pair<std::string, double>> values;
};

// The solution Problem/Theory names, with the FE quantities compared against it.
Theory classical_theory(const Parameters& prm, const std::vector<QuantitySummary>& quantities);
} // namespace pdfem
