#pragma once
// The layer of one subject (docs/meshing.md, "Every mesher at every thickness"). The template layer, meshed once at
// β = 0, is retargeted to the subject's shape and thickness; where that would invert tets (a thick layer on a
// strongly shaped body, more often with the unstructured cgal and gmsh meshes) the subject's own layer is meshed
// instead: the shaped body itself becomes the template (its β = 0 is the subject's β), meshed at the thickness
// field's mean and cached per subject and thickness like any template, then retargeted to the thickness field.
// Vertex indices, faces, regions and skinning weights are the body's, so everything downstream (material fields,
// skinning, output on the body's surface) is unchanged; only the tets differ.
#include <sflsh/body/body_model.hpp>
#include <sflsh/meshing/layer_mesh.hpp>
#include <sflsh/meshing/retarget.hpp>

#include <filesystem>
#include <memory>
#include <string>

namespace sflsh::meshing {

/// A copy of `model` whose template is its shape β (v_template = shaped_template(model, β)), named
/// "<name>-shape-<hash of β>" so that its layer meshes are cached apart from the template's.
body::BodyModel subject_body(const body::BodyModel& model, const body::Betas& beta);

/// A retargeted layer with the mesh and retargeter it came from (both on the heap: the retargeter refers to them).
struct SubjectLayer {
  std::unique_ptr<body::BodyModel> subject;  ///< the shaped body the mesh was built on (remeshed layers only)
  std::unique_ptr<LayerMesh> mesh;
  std::unique_ptr<Retargeter> retargeter;
  RetargetedLayer layer;
  bool remeshed = false;         ///< the template inverted tets; the subject's own layer was meshed
  std::string template_failure;  ///< the template's retarget error when remeshed
  std::string fallback;          ///< when remeshed: which layer replaced the template (subject_layer.cpp, fallbacks)
};

/// The layer of shape β with thickness field h (one value per region vertex of `template_mesh`): the template
/// retargeted, or the subject's own layer (see the file comment) when that throws. `options` are the template's
/// (mesher, size, region, threads); the subject mesh is meshed at mean(h) rounded to 0.05, else at the template's h.
/// Throws the template's error, with the subject mesh's appended, when both fail.
SubjectLayer subject_layer(const body::BodyModel& model, LayerMesh template_mesh, const body::Betas& beta,
                           const Eigen::VectorXd& thickness, const LayerMeshOptions& options,
                           const std::filesystem::path& cache_dir);

}  // namespace sflsh::meshing
