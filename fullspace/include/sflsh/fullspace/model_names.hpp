#pragma once
// The model library's problem vocabulary (sflsh::model, model/) under the names the full-space solvers use.
// Declarations only: every concept is defined once, in model/.
#include <sflsh/model/problem.hpp>
#include <sflsh/model/step_stats.hpp>

namespace sflsh::fullspace {

using model::Dirichlet;
using model::ElasticEvaluation;
using model::Energies;
using model::energies;
using model::evaluate_elastic;
using model::initial_state;
using model::lumped_masses;
using model::NodeFrame;
using model::NodePotential;
using model::NodeTrajectory;
using model::posed_positions;
using model::Problem;
using model::RowMatrixX3d;
using model::RowMatrixX4i;
using model::ScalarDrive;
using model::State;
using model::StepStats;

}  // namespace sflsh::fullspace
