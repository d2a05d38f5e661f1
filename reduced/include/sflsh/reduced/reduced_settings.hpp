#pragma once
// The reduced-model settings a user gives (cubature weights, affine handles) and the model options of one
// configuration (handles, cubature, cache). The command line (--cubature-weights, --affine, --handles, …) and
// the Python module share this one definition; the messages name the command-line options.
#include <sflsh/reduced/reduced_model.hpp>

#include <string>
#include <vector>

namespace sflsh::reduced {

/// The reduced-model options that do not change along a sweep.
struct ReducedSettings {
  std::string cubature_weights = "nnls";  ///< nnls | voronoi
  bool affine = false;
};

/// Options of one reduced model: `handles` point handles, `cubature` tets (0 = every tet, −1 = auto); `cache`
/// empty: the default cache folder.
ReducedModelOptions reduced_model_options(const ReducedSettings& settings, int handles, int cubature,
                                          const std::string& cache);

/// Throws a one-line error naming the largest count when a handle count exceeds what the layer allows.
void check_handle_counts(const model::BodyLayer& layer, const std::vector<int>& handles);

}  // namespace sflsh::reduced
