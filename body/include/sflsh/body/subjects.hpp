#pragma once
// Named subjects (β vectors): the paper's Table 1 (DYNA 1–5 train, TEST 1–5) in data/subjects.toml,
// and the open body's own train/test subjects in data/open_body_subjects.toml (written by
// `sflsh body generate`).
#include <sflsh/body/skinning.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace sflsh::body {

struct Subject {
  std::string name;   ///< e.g. "DYNA_1", "TEST_3", "OPEN_TRAIN_2"
  std::string split;  ///< "train" or "test"
  std::string body;   ///< body model the β refers to: "smpl" (paper) or "open"
  std::string description;
  Betas beta = Betas::Zero();
};

/// Reads a subjects file ([[subject]] tables with name, split, body, description, beta = [10 numbers]).
/// Errors name the file, the line and the field.
std::vector<Subject> load_subjects(const std::filesystem::path& path);

/// Writes a subjects file atomically, with `header` as a leading comment block.
void save_subjects(const std::filesystem::path& path, const std::vector<Subject>& subjects, const std::string& header);

/// All shipped subjects: data/subjects.toml followed by data/open_body_subjects.toml (when present).
std::vector<Subject> default_subjects();

/// The subject named `name` (case-sensitive); the error lists the known names.
const Subject& find_subject(const std::vector<Subject>& subjects, const std::string& name);

/// Parses "b1 b2 … b10" (spaces and/or commas; fewer than 10 values are zero-padded, more is an error).
Betas parse_betas(const std::string& text);

}  // namespace sflsh::body
