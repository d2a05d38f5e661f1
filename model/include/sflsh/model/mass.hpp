#pragma once
// Mass of a linear-tet mesh (docs/physics.md §5, docs/integrators.md): the consistent matrix M_ij = ρ∫N_iN_j dV,
// per tet ρV/20 (1 + δ_ab) for its node pair (a, b), and the lumped diagonal ρV/4 per node, which is the row
// sum of the consistent one (so gravity, Σ_j M_ij g = m_i g, is the same for both). Both act on each axis of
// the posed positions: the kinetic energy is ½ Σ_ij M_ij ṗ_i·ṗ_j.
#include <sflsh/meshing/types.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <string_view>

namespace sflsh::model {

enum class MassKind { lumped, consistent };

/// "lumped" | "consistent"; anything else throws sflsh::Error naming `where` and the accepted values.
MassKind parse_mass_kind(std::string_view text, std::string_view where);
std::string_view to_string(MassKind kind);

/// The mass of every body run that names none (time_integrator.hpp kDefaultIntegrator; docs/decisions.md).
inline constexpr MassKind kDefaultMassKind = MassKind::consistent;
/// The paper's mass: lumped, ρV/4 per node.
inline constexpr MassKind kPaperMassKind = MassKind::lumped;

/// M_e(a, b) / (ρV_e): 1/10 on the diagonal, 1/20 off it (the consistent mass of a linear tet).
inline double consistent_mass_factor(int a, int b) { return a == b ? 0.1 : 0.05; }

/// ρ V_e per tet [kg].
Eigen::VectorXd tet_masses(const meshing::RowMatrixX3d& rest, const meshing::RowMatrixX4i& tets, double density);

/// The node-level consistent matrix (N × N, one entry per node pair sharing a tet) [kg] from ρV_e per tet.
Eigen::SparseMatrix<double, Eigen::RowMajor> consistent_mass_matrix(const meshing::RowMatrixX4i& tets,
                                                                    const Eigen::VectorXd& tet_mass, int num_nodes);

}  // namespace sflsh::model
