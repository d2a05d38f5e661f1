#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subject_selection.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/input_file.hpp>
#include <sflsh/core/log.hpp>

namespace sflsh::body {

BodyModel load_selected_body(const SubjectSelection& selection) {
  const std::filesystem::path path =
      selection.body_path.empty() ? default_body_path() : std::filesystem::path(selection.body_path);
  if (selection.body_path.empty() && !std::filesystem::exists(path)) {
    throw_error("{}: the open body is missing; regenerate it with `sflsh body generate`", path.string());
  }
  if (!selection.body_path.empty()) require_input_file(path, "a body model .npz file");
  BodyModel model = load_body(path);
  logger()->debug("body {}: {} vertices, {} faces", path.string(), model.num_vertices(), model.num_faces());
  return model;
}

Betas selected_betas(const SubjectSelection& selection, std::string& label, const char* required_by) {
  const bool none = selection.subject.empty() && selection.betas.empty() && !selection.beta_values;
  if (required_by && none) throw_error("{}: one of --subject NAME or --betas \"b1 … b10\" is required", required_by);
  if (!selection.subject.empty()) {
    const auto subjects = default_subjects();
    label = selection.subject;
    return find_subject(subjects, selection.subject).beta;
  }
  if (!selection.betas.empty()) {
    label = "betas";
    return parse_betas(selection.betas);
  }
  if (selection.beta_values) {
    require(selection.beta_values->allFinite(), "--betas: the values are not all finite");
    label = "betas";
    return *selection.beta_values;
  }
  label = "template";
  return Betas::Zero();
}

std::string body_label(const SubjectSelection& selection) {
  return selection.body_path.empty() ? std::string("open_body") : selection.body_path;
}

}  // namespace sflsh::body
