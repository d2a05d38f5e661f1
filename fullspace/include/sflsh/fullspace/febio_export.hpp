#pragma once
// A verification problem (verify_problem.hpp) as a FEBio 4 input file (febio_spec 4.0), so the identical problem
// runs in FEBio (`sflsh verify PROBLEM.toml --export-febio FILE.feb`, docs/fullspace.md). The layout follows
// tests/data/febio_export/example_block_fung_tet4g4.feb, the input behind FEBio 4.11's run of the driven block.
//
//   [material] (fung_scale ≠ "none")  → 'Fung-ortho-compressible': E1 = E2 = Y_t, E3 = Y_n, G12 = Y_t/(2(1+ν)),
//                                         G23 = G31 = √(Y_t Y_n)/(2(1+ν)), v12 = ν, v23 = ν√(Y_t/Y_n),
//                                         v31 = ν√(Y_n/Y_t), c = fung_scale_c, k = 1e-3 Pa (FEBio refuses 0)
//   [material] fung_scale = "none"    → 'orthotropic elastic' with the same E, G, v
//   normal ≠ +z                       → <mat_axis type="vector"> with a ⟂ n, d = n × a (FEBio's third axis a × d = n)
//   mesh                              → TET4G4 elements (the exact consistent mass), one NodeSet per node group
//   [[fix]] / [[drive]]               → 'zero displacement' / 'prescribed displacement' + a 'math' load controller
//   gravity g                         → body_load 'body force' with force = −g (FEBio's sign)
//   density > 0 / 0                   → DYNAMIC (trapezoidal Newmark, β = 1/4, γ = 1/2) / STATIC, full Newton
//   [record]                          → a logfile node_data of ux;uy;uz on the record group
//
// What FEBio integrates differently (lumped mass, an integrator other than "newmark", a drive that does not start
// at rest, overflow = "continue_linearly", nodes in no tet) is written as an XML comment and returned as a warning.
#include <sflsh/fullspace/verify_problem.hpp>

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace sflsh::fullspace {

/// FEBio's bulk modulus k [Pa] of 'Fung-ortho-compressible' (W gains ½k(ln J)², which our energy lacks). FEBio
/// refuses k = 0; against Y_t of kPa, 1e-3 Pa changes nothing measurable (k = 1e-12 gives the same trajectories).
inline constexpr double kFebioBulkModulus = 1e-3;

/// The .feb text and the differences between the two codes that it records.
struct FebioInput {
  std::string xml;                    ///< the FEBio 4 input (ISO-8859-1 declared, ASCII written)
  std::vector<std::string> warnings;  ///< one line each, also XML comments in `xml`
};

/// The verification problem as a FEBio 4 input. `log_stem` names FEBio's log of the record group,
/// "<log_stem>_<record group>.txt" next to the .feb file. Throws sflsh::Error naming the problem file for a
/// duration that is not a whole number of steps and for a drive FEBio cannot parse (febio_math_expression).
FebioInput febio_input(const VerifyProblem& spec, std::string_view log_stem);

/// Writes febio_input(spec, path's stem) to `path` atomically and logs each warning. Nothing is written when
/// the problem cannot be exported.
void write_febio_input(const VerifyProblem& spec, const std::filesystem::path& path);

/// A muparser expression of t (verify_problem.hpp: constants pi, e) in the syntax of FEBio's math parser
/// (its 'math' load controller), with parentheses wherever the two grammars could read it differently (FEBio's `^`
/// is left-associative, muparser's right-associative). Functions: the common ones by name, muparser's log → ln,
/// log10 → log, log2(x) → ln(x)/ln(2), sign(x) → H(x)−H(−x), sum → +; _pi, _e → pi, e; unary + dropped.
/// Throws sflsh::Error "uses <construct>, which FEBio's math parser lacks" for ?:, comparisons, && and ||,
/// assignments, several comma-separated expressions, asinh, atanh, rint, and for a result longer than FEBio's
/// 511-character buffer.
std::string febio_math_expression(std::string_view expression);

}  // namespace sflsh::fullspace
