#include <sflsh/core/error.hpp>
#include <sflsh/reduced/reduced_settings.hpp>

namespace sflsh::reduced {

ReducedModelOptions reduced_model_options(const ReducedSettings& s, int handles, int cubature,
                                          const std::string& cache) {
  ReducedModelOptions o;
  o.point_handles = handles;
  o.cubature = cubature;
  o.weighting = s.cubature_weights == "voronoi" ? CubatureWeighting::voronoi : CubatureWeighting::nnls;
  o.basis.affine = s.affine;
  if (!cache.empty()) o.cache_dir = cache;
  return o;
}

void check_handle_counts(const model::BodyLayer& layer, const std::vector<int>& handles) {
  const int most = max_point_handles(layer);
  for (int h : handles) require(h <= most, "reduced: {} point handles requested; the layer allows 1 to {}", h, most);
}

}  // namespace sflsh::reduced
