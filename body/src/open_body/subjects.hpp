#pragma once
// The open body's named subjects, defined in anthropometric-factor space.
#include <sflsh/body/open_body.hpp>

#include <vector>

namespace sflsh::body::detail {

/// OPEN_TRAIN_1..5 and OPEN_TEST_1..5 with name, split, description and factors (β left zero; the
/// generator projects each subject onto its PCA basis).
std::vector<OpenBodySubject> open_body_subject_definitions();

}  // namespace sflsh::body::detail
