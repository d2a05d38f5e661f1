#pragma once
// The state of the SUNDIALS reference integrator (reference_integrator.hpp), shared by its two sources:
// reference_integrator.cpp (pattern, right side, Jacobian, the ARKODE driver) and reference_integrator_mass.cpp
// (the consistent mass: M_y, its KLU solver, the Newton matrix M_y − γJ). Layout of y and of the Jacobian pattern:
// reference_integrator.cpp.
#include "reference_mass.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>

#include <arkode/arkode_arkstep.h>
#include <fmt/format.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <array>
#include <limits>
#include <string>
#include <vector>

namespace sflsh::fullspace {

struct ReferenceIntegrator::Impl {
  const Problem& problem;
  ReferenceOptions options;
  int n = 0;                                             // nodes
  sunindextype nx = 0;                                   // 3N
  std::vector<char> constrained;                         // per x dof
  std::vector<int> constraint_count;                     // per node: how many of its components are prescribed
  std::vector<double> inv_mass;                          // per node; 0 for fully prescribed massless nodes
  bool consistent = false;                               // M_y ẏ = f with the consistent mass (reference_mass.hpp)
  detail::ComponentMass component_mass;                  // M_w and M_FC (consistent only)
  std::vector<sunindextype> mass_row_ptr, mass_col_idx;  // M_y = diag(I, M_w) in CSR (consistent only)
  std::vector<double> mass_values;
  std::vector<double> mass_on_pattern;  // M_y on the pattern of J (consistent only)
  std::vector<double> saved_values;     // J of the last Jacobian evaluation (consistent: ARKODE's jok reuse)
  double t_start = 0.0;                 // of the run: the prescribed accelerations are not differenced before it
  double acceleration_time = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd coupling_force;  // M_FC a_C(acceleration_time) [N]

  // Jacobian pattern (CSR) and per-tet positions of the node-pair blocks in the w rows.
  std::vector<sunindextype> row_ptr, col_idx;
  std::vector<std::vector<int>> neighbours;    // sorted, including the node itself
  std::vector<std::array<int, 16>> tet_block;  // (a, b) ↦ index of node b in neighbours[node a]

  // Scratch reused by the callbacks.
  NodeFrame frame, rate;
  Eigen::VectorXd x_eff, du;
  std::vector<Eigen::Matrix3d> A_inv;  // per node
  std::vector<double> values;

  // SUNDIALS objects.
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  SUNMatrix jac = nullptr;
  SUNLinearSolver solver = nullptr;
  SUNMatrix mass = nullptr;               // consistent only
  SUNLinearSolver mass_solver = nullptr;  // consistent only
  void* arkode = nullptr;

  double t = 0.0;
  bool ready = false;  // initialized and not failed
  ReferenceStats stats;
  std::string last_arkode_error;  // from the error handler
  std::string last_rhs_problem;   // why the RHS or the Jacobian last refused

  Impl(const Problem& p, const ReferenceOptions& o) : problem(p), options(o) {}
  ~Impl() {
    if (arkode != nullptr) ARKStepFree(&arkode);
    if (mass_solver != nullptr) SUNLinSolFree(mass_solver);
    if (mass != nullptr) SUNMatDestroy(mass);
    if (solver != nullptr) SUNLinSolFree(solver);
    if (jac != nullptr) SUNMatDestroy(jac);
    if (y != nullptr) N_VDestroy(y);
    if (ctx != nullptr) SUNContext_Free(&ctx);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  /// Throws sflsh::Error naming the call, ARKODE's flag and its last message when flag < 0.
  void check(int flag, const char* call) const;

  void build_pattern();
  /// M_w, M_FC, M_y in CSR and M_y on the pattern of J (consistent mass; after build_pattern).
  void build_mass();
  /// coupling_force = M_FC a_C(t_eval), reused while t_eval repeats (Newton iterations of one stage).
  /// Returns 0 or −1 (the forcing is not finite) with the reason in last_rhs_problem.
  int update_coupling(double t_eval);
  /// Consistent mass: ρV per tet whose row sums are the lumped masses; throws sflsh::Error otherwise.
  void check_consistent_mass() const;
  /// Consistent mass: the SUNDIALS matrix M_y and its KLU solver (after build_mass and the context).
  void create_mass_solver();
  /// The frame, its rate, x with the prescribed values and du/dt at time t into the scratch members.
  /// Returns 0 or −1 (unrecoverable: non-finite forcing, bad input) with the reason in last_rhs_problem.
  int prepare(double t_eval, const double* x);
  /// Inside a catch block: ARKODE's status for the exception in flight, 1 (recoverable: a smaller step) for an
  /// sflsh::Error, −1 for any other, with its message in last_rhs_problem.
  int refusal();
  int rhs(double t_eval, const double* yv, double* ydot);
  /// J = ∂f/∂y into `values` (on the fixed pattern).
  int jacobian(double t_eval, const double* yv);
  State output_state(double t_out) const;
  void collect_stats();

  // The C callbacks; user_data is the Impl.
  static int rhs_callback(sunrealtype t_eval, N_Vector yv, N_Vector ydot, void* user_data) {
    return static_cast<Impl*>(user_data)->rhs(t_eval, NV_DATA_S(yv), NV_DATA_S(ydot));
  }
  static int jacobian_callback(sunrealtype t_eval, N_Vector yv, N_Vector /*fy*/, SUNMatrix J, void* user_data,
                               N_Vector /*tmp1*/, N_Vector /*tmp2*/, N_Vector /*tmp3*/) {
    auto* impl = static_cast<Impl*>(user_data);
    if (SM_NNZ_S(J) < static_cast<sunindextype>(impl->col_idx.size()) || SM_ROWS_S(J) != 2 * impl->nx) {
      impl->last_rhs_problem = "the Jacobian matrix lost its storage";
      return -1;
    }
    if (const int status = impl->jacobian(t_eval, NV_DATA_S(yv)); status != 0) return status;
    // ARKODE zeroes the matrix (pattern included) before calling us: write pattern and values.
    std::copy(impl->row_ptr.begin(), impl->row_ptr.end(), SM_INDEXPTRS_S(J));
    std::copy(impl->col_idx.begin(), impl->col_idx.end(), SM_INDEXVALS_S(J));
    std::copy(impl->values.begin(), impl->values.end(), SM_DATA_S(J));
    return 0;
  }
  /// M_y into ARKODE's mass matrix (consistent mass; reference_integrator_mass.cpp).
  static int mass_callback(sunrealtype t_eval, SUNMatrix M, void* user_data, N_Vector tmp1, N_Vector tmp2,
                           N_Vector tmp3);
  /// The Newton matrix M_y − γJ on J's pattern; J is re-evaluated unless ARKODE allows reuse (jok).
  static int linear_system_callback(sunrealtype t_eval, N_Vector yv, N_Vector fy, SUNMatrix A, SUNMatrix M,
                                    sunbooleantype jok, sunbooleantype* jcur, sunrealtype gamma, void* user_data,
                                    N_Vector tmp1, N_Vector tmp2, N_Vector tmp3);
  static void error_callback(int error_code, const char* module, const char* function, char* message, void* user_data) {
    if (error_code == ARK_WARNING) return;  // e.g. "t + h = t": no exception for that, and stderr stays quiet
    static_cast<Impl*>(user_data)->last_arkode_error =
        fmt::format("[{}::{}] {}", module != nullptr ? module : "?", function != nullptr ? function : "?",
                    message != nullptr ? message : "");
  }
};

}  // namespace sflsh::fullspace
