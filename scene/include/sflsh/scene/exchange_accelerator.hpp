#pragma once
// The exchange of end-of-step surfaces between touching bodies. Within a step the
// touching bodies are solved again and again, each from its start-of-step state against the others' surfaces
// of the previous exchange (block Jacobi: the order of the bodies plays no part), until the surfaces they are
// solved against are the surfaces they give: a fixed point x = H(x) of the stacked surfaces x. The plain
// exchange x ← H(x) converges slowly or not at all (each body alone would give way by the whole overlap), so the
// next x comes from an interface quasi-Newton step (IQN-ILS, Degroote, Bruggeman, Haelterman, Vierendeels 2009;
// Anderson acceleration): the differences of the earlier residuals r = H(x) − x and outputs H(x) fit a least-
// squares model of the inverse Jacobian, and the first exchange is relaxed by ω₀.
#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace sflsh::scene {

class ExchangeAccelerator {
 public:
  /// first_relaxation: ω₀ of the first update x + ω₀ r (½ splits an overlap evenly between two like bodies);
  /// max_columns: the most recent differences kept.
  explicit ExchangeAccelerator(double first_relaxation = 0.5, int max_columns = 10);

  /// x: what the bodies were solved against; output = H(x): what they gave. Returns the next x:
  ///   x + ω₀ r on the first call, else H(x) + W c with c = argmin ‖V c + r‖
  /// (V, W: differences of the earlier residuals and outputs).
  Eigen::VectorXd next(const Eigen::VectorXd& x, const Eigen::VectorXd& output);

  int columns() const { return static_cast<int>(residual_differences_.size()); }

 private:
  double first_relaxation_;
  int max_columns_;
  std::vector<Eigen::VectorXd> residual_differences_, output_differences_;
  Eigen::VectorXd last_residual_, last_output_;
};

/// The touching clusters of a group: bodies i, j are linked when i's body-contact potential has a candidate
/// near j's surface or j's near i's (`touches[i]` lists the bodies i's candidates are near). Returns the linked
/// components with two or more bodies, each ascending, in the order of their first body.
std::vector<std::vector<std::size_t>> touching_clusters(const std::vector<std::size_t>& group,
                                                        const std::vector<std::vector<std::size_t>>& touches);

}  // namespace sflsh::scene
