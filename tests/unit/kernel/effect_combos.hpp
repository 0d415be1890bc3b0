// The 24 effect combinations the force kernel is compiled for (stretch measure × plasticity ×
// damage × uniform or per-bond field), shared by the kernel tests that loop over all of them.
#pragma once

#include "libpd/physics/effects.hpp"

#include <string>
#include <vector>

namespace pd::test {

struct Combo {
  StretchKind stretch;
  bool plasticity;
  bool damage;
  bool per_bond;

  std::string label() const {
    return pd::to_string(stretch) + (plasticity ? " plastic" : " elastic") +
           (damage ? " damage" : "") + (per_bond ? " per-bond" : " uniform");
  }
};

inline std::vector<Combo> all_combos() {
  std::vector<Combo> out;
  for (StretchKind s : {StretchKind::exact, StretchKind::modified, StretchKind::fast}) {
    for (bool p : {false, true}) {
      for (bool d : {false, true}) {
        for (bool f : {false, true}) {
          out.push_back({s, p, d, f});
        }
      }
    }
  }
  return out;
}

} // namespace pd::test
