#pragma once
// The motion the node maps and the prescribed components impose on an elastic state (docs/physics.md §5):
//   ṗ_i = Ȧ_i x_i + ḋ_i + A_i ẋ_i,   ẋ = du/dt on prescribed components, 0 elsewhere,
// and its time derivative with the free components of x held fixed (the prescribed ones follow u(t)).
#include <sflsh/model/problem.hpp>

namespace sflsh::model {

/// ṗ at time t [s] for the elastic state x (3N; its prescribed components are taken at t) [m/s].
Eigen::VectorXd kinematic_velocity(const Problem& problem, const Eigen::VectorXd& x, double t);

/// d/dt of kinematic_velocity at fixed free components of x: a forward difference over 1 µs (the forcing is C¹,
/// cubic Hermite joints, so its jerk is bounded) [m/s²].
Eigen::VectorXd kinematic_acceleration(const Problem& problem, const Eigen::VectorXd& x, double t);

}  // namespace sflsh::model
