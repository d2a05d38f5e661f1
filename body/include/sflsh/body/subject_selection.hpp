#pragma once
// Which body model and which subject a run is about: a body .npz (default: the open body) and a named subject,
// a β text or β values. The command line (--body, --subject, --betas) and the Python module (Body, Simulation)
// choose a subject through this one definition, so both read the same body, the same β and the same label.
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/skinning.hpp>

#include <optional>
#include <string>

namespace sflsh::body {

struct SubjectSelection {
  std::string body_path;             ///< body model .npz; empty: the open body (default_body_path())
  std::string subject;               ///< a named subject (data/subjects.toml, data/open_body_subjects.toml)
  std::string betas;                 ///< β as text, "b1 b2 … b10" (parse_betas)
  std::optional<Betas> beta_values;  ///< β as numbers (callers that hold an array); used when `betas` is empty
};

/// The body model of the selection. An explicit path must be a readable file ("a body model .npz file");
/// a missing open body names `sflsh body generate`.
BodyModel load_selected_body(const SubjectSelection& selection);

/// The β of the subject, the β text or the β values; `label` receives the subject's name, "betas" or "template".
/// When none is given: an error naming `required_by` if it is not null, else β = 0.
Betas selected_betas(const SubjectSelection& selection, std::string& label, const char* required_by = nullptr);

/// What summaries call the body: "open_body" or the path given.
std::string body_label(const SubjectSelection& selection);

}  // namespace sflsh::body
