#pragma once
// The Fung exponent together with the size of the scaled strain it comes from, from one evaluation: what a
// guard that bounds how far the exponent can move needs (reduced/cubature_guard.hpp).
#include <sflsh/material/orthotropic_fung.hpp>

namespace sflsh::material {

struct FungStrain {
  double exponent = 0.0;       ///< x = 2Ψ₀/c (0 when the Fung factor is off), as fung_exponent()
  double scaled_strain = 0.0;  ///< ‖Ê‖_F, Ê = P_Y E P_Y [Pa^½]
};

/// Throws sflsh::Error on a non-finite F or an overflowing StVK energy, as fung_exponent().
FungStrain fung_strain(const Eigen::Matrix3d& F, const OrthotropicFung& m);

}  // namespace sflsh::material
