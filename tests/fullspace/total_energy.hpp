#pragma once
// The energy an undamped, unforced run conserves: kinetic + elastic + gravity (model::energies) [J].
#include <sflsh/model/problem.hpp>

namespace sflsh::testing {

inline double total_energy(const model::Problem& p, const model::State& s) {
  const model::Energies e = model::energies(p, s);
  return e.kinetic + e.elastic + e.gravity;
}

}  // namespace sflsh::testing
