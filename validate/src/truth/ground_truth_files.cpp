#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/validate/dyna_file.hpp>
#include <sflsh/validate/ground_truth.hpp>
#include <sflsh/validate/true_material.hpp>

#include <map>

namespace sflsh::validate {

void write_ground_truth_files(RunFolder& run, const body::BodyModel& model, const meshing::LayerMesh& mesh,
                              const std::vector<const GroundTruthCase*>& cases, const material::ParameterBounds& bounds,
                              const TrueMaterial& truth) {
  require(!cases.empty(), "ground truth: no cases to write");
  std::vector<DynaSequence> sequences;
  std::map<std::string, const GroundTruthCase*> subjects;
  for (const GroundTruthCase* c : cases) {
    require(!c->posed.empty(), "ground truth {} / {}: no posed frames kept", c->subject, c->motion);
    DynaSequence s;
    s.key = c->subject + "_" + c->motion;
    s.frames = c->posed;
    s.fps = c->fps;
    s.attributes.numbers["fps"] = {c->fps};
    s.attributes.numbers["beta"] = std::vector<double>(c->beta.data(), c->beta.data() + c->beta.size());
    s.attributes.numbers["sigma_mean_mm"] = {c->mean_sigma()};
    sequences.push_back(std::move(s));
    subjects.emplace(c->subject, c);
  }
  Attributes file;
  file.strings["source"] = "sflsh synthetic ground truth";
  file.strings["body"] = model.name;
  file.strings["true_material"] = truth.description();
  write_dyna_file(run.stage("groundtruth.h5"), model.faces, sequences, file);

  const std::vector<int>& region = mesh.region_surface.vertices;
  std::vector<std::int64_t> region64(region.begin(), region.end());
  for (const auto& [name, c] : subjects)
    npz::write(run.stage("truth/" + name + ".npz"), {{"region_vertices", npz::make_i64({region64.size()}, region64)},
                                                     {"kappa", npz::make_f64(Eigen::MatrixXd(c->kappa))},
                                                     {"beta", npz::make_f64(Eigen::MatrixXd(c->beta.transpose()))}});
  nlohmann::json j;
  j["description"] = truth.description();
  j["columns"] = {"thickness", "young_tangent_pa", "young_normal_pa"};
  j["bounds"] = {{"thickness", {bounds.thickness.min, bounds.thickness.max}},
                 {"young_tangent", {bounds.young_tangent.min, bounds.young_tangent.max}},
                 {"young_normal", {bounds.young_normal.min, bounds.young_normal.max}}};
  for (const auto& [name, c] : subjects)
    j["subjects"][name] = {{"beta", std::vector<double>(c->beta.data(), c->beta.data() + c->beta.size())},
                           {"mean_kappa", {c->kappa.col(0).mean(), c->kappa.col(1).mean(), c->kappa.col(2).mean()}}};
  write_json(run.stage("truth/true_material.json"), j);
}

}  // namespace sflsh::validate
