#pragma once
// The hidden material of the synthetic ground truth: κ(s, β) = (h, Y_t, Y_n) at every region vertex of a
// subject, smooth over the template surface and smoothly shape-dependent through the local outward offset
// of the shaped surface, d(s, β) = n̄(s) · B(s) β [m] (n̄: template normal, B: shape blend-shape block):
//   h   = 0.36 + 0.06 sin(5 y + 1) + 4 d                   (2 cm more flesh → h + 0.08)
//   Y_t = 7 kPa · exp(0.35 sin(4 x + 3 y)) · exp(−25 d)    (2 cm more flesh → 39 % softer)
//   Y_n = 0.45 · Y_t · exp(0.25 cos(6 y))
// with (x, y) the template position [m], each clamped 2 % inside the parameter ranges. It lives on the
// vertices, not in the span of any control-point basis, so a fit cannot reproduce it exactly — as with
// real tissue — and recovered parameters can be compared with it.
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/material/parameters.hpp>
#include <sflsh/meshing/layer_mesh.hpp>

#include <string>

namespace sflsh::validate {

/// κ per region vertex (R × 3, physical) of subject β.
material::KappaMatrix true_kappa_field(const body::BodyModel& model, const meshing::LayerMesh& mesh,
                                       const body::Betas& beta, const material::ParameterBounds& bounds);

/// The formulas above as text (written beside the ground truth).
std::string true_material_description();

}  // namespace sflsh::validate
