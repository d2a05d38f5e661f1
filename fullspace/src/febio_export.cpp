// FEBio 4 input files of verification problems (febio_export.hpp), in the element order and spelling of
// tests/data/febio_export/example_block_fung_tet4g4.feb, with FEBio 4's input keywords (the mapping:
// docs/fullspace.md, "FEBio input"; what it gives: docs/verification.md).
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/fullspace/febio_export.hpp>
#include <sflsh/material/skin_material.hpp>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace sflsh::fullspace {

namespace {

/// The shortest decimal that reads back as the same double (fmt's default): full precision.
std::string febio_number(double value) { return fmt::format("{}", value); }

std::string febio_vector(const Eigen::Vector3d& v) {
  return febio_number(v.x()) + "," + febio_number(v.y()) + "," + febio_number(v.z());
}

/// Text and attribute values with XML's five special characters escaped.
std::string xml_escaped(std::string_view text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

/// A node group's name as part of a file name: letters, digits, '.', '-' and '_' kept, the rest '_'.
std::string file_name_part(std::string_view name) {
  std::string out(name);
  for (char& c : out) {
    if (std::isalnum(static_cast<unsigned char>(c)) == 0 && c != '.' && c != '-' && c != '_') c = '_';
  }
  return out;
}

/// 1-based ids, comma separated.
std::string one_based_list(const std::vector<int>& nodes) {
  std::string out;
  for (const int v : nodes) {
    if (!out.empty()) out += ',';
    out += std::to_string(v + 1);
  }
  return out;
}

class FebioWriter {
 public:
  FebioWriter(const VerifyProblem& spec, std::string_view log_stem) : spec_(spec), log_stem_(log_stem) {}

  FebioInput write() {
    out_ = "<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>\n";
    comment("", fmt::format("sflsh verify {} (mesh {}) as a FEBio 4 input: run it with febio4 -i FILE.feb",
                            spec_.file.filename().string(), spec_.mesh_path.filename().string()));
    out_ += "<febio_spec version=\"4.0\">\n  <Module type=\"solid\"/>\n";
    control();
    material();
    mesh();
    out_ += "  <MeshDomains><SolidDomain name=\"flesh\" mat=\"flesh\"/></MeshDomains>\n";
    boundary();
    loads();
    output();
    out_ += "</febio_spec>\n";
    return {std::move(out_), std::move(warnings_)};
  }

 private:
  const VerifyProblem& spec_;
  std::string log_stem_;
  std::string out_;
  std::vector<std::string> warnings_;

  /// An XML comment on its own line (ASCII, "--" broken up, as XML requires).
  void comment(std::string_view indent, std::string text) {
    for (std::size_t at = text.find("--"); at != std::string::npos; at = text.find("--")) text.replace(at, 2, "- -");
    if (!text.empty() && text.back() == '-') text += ' ';
    out_ += fmt::format("{}<!-- {} -->\n", indent, text);
  }

  /// A difference between the two runs: an XML comment here and a warning.
  void note(std::string_view indent, const std::string& text) {
    comment(indent, "sflsh/FEBio difference: " + text);
    warnings_.push_back(text);
  }

  void control() {
    const bool dynamic = spec_.density > 0.0;
    require(spec_.duration / spec_.step < 1e15, "{}: time.step: {} s gives more than 1e15 steps over {} s",
            spec_.file.string(), spec_.step, spec_.duration);
    const long long steps = std::llround(spec_.duration / spec_.step);
    require(steps >= 1 && std::abs(static_cast<double>(steps) * spec_.step - spec_.duration) <=
                              1e-9 * std::max(1.0, spec_.duration),
            "{}: time.duration = {} is not a whole number of steps of {}", spec_.file.string(), spec_.duration,
            spec_.step);
    out_ += "  <Control>\n";
    out_ += fmt::format("    <analysis>{}</analysis>\n", dynamic ? "DYNAMIC" : "STATIC");  // density 0 = static
    out_ += fmt::format("    <time_steps>{}</time_steps>\n", steps);                       // duration / step
    out_ += fmt::format("    <step_size>{}</step_size>\n", febio_number(spec_.step));
    out_ += "    <plot_level>PLOT_NEVER</plot_level>\n";
    if (dynamic && spec_.mass == model::MassKind::lumped) {
      note("    ",
           "mass = \"lumped\" (rho V/4 per node): FEBio has no lumped mass for solids and integrates the "
           "consistent mass (exact under TET4G4); use mass = \"consistent\" for the same equations");
    }
    if (dynamic && spec_.integrator != VerifyProblem::Integrator::newmark) {
      note("    ", fmt::format("integrator = \"{}\": FEBio's DYNAMIC solid analysis integrates with trapezoidal "
                               "Newmark (beta 1/4, gamma 1/2) at the fixed step, which is sflsh's \"newmark\"",
                               to_string(spec_.integrator)));
    }
    // Full Newton (a new stiffness every iteration, no BFGS updates), as in the example.
    out_ += "    <solver type=\"solid\">\n";
    out_ += "      <symmetric_stiffness>symmetric</symmetric_stiffness>\n";
    out_ += "      <max_refs>100</max_refs>\n";
    out_ += "      <qn_method type=\"BFGS\"><max_ups>0</max_ups></qn_method>\n";
    out_ += "      <dtol>1e-9</dtol><etol>1e-12</etol><rtol>0</rtol><lstol>0.9</lstol>\n";
    if (dynamic) {
      // FESolidSolver2's defaults written out: rhoi = -2 keeps alpha = 1 and these, the trapezoidal rule.
      comment("      ", "Newmark beta = 1/4, gamma = 1/2: the trapezoidal rule of sflsh's integrator \"newmark\"");
      out_ += "      <beta>0.25</beta><gamma>0.5</gamma>\n";
    }
    out_ += "    </solver>\n  </Control>\n";
  }

  void material() {
    const material::SkinMaterial& m = spec_.material;
    const material::OrthotropicConstants k = material::small_strain_constants(m);
    const bool fung = std::isfinite(k.c);
    out_ += "  <Material>\n";
    comment("    ",
            fmt::format("sflsh [material] young_tangent Y_t = {} Pa, young_normal Y_n = {} Pa, poisson nu = {}, "
                        "saturation = {}, normal = ({}): E1 = E2 = Y_t, E3 = Y_n, G12 = Y_t/(2(1+nu)), G23 = "
                        "G31 = sqrt(Y_t Y_n)/(2(1+nu)), v12 = nu, v23 = nu sqrt(Y_t/Y_n), v31 = nu "
                        "sqrt(Y_n/Y_t), axis 3 = the normal",
                        febio_number(m.young_tangent), febio_number(m.young_normal), febio_number(m.poisson),
                        febio_number(m.saturation), febio_vector(spec_.normal)));
    if (fung) {
      comment("    ", fmt::format("Fung-ortho-compressible, W = c/2 (exp(Q) - 1) + k/2 ln(J)^2, is sflsh's "
                                  "(c/2)(exp(2 Psi0/c) - 1) plus the k term: c = {} Pa; k = {} Pa because FEBio "
                                  "refuses k = 0 (sflsh has no bulk term; k = 1e-12 changes nothing measurable)",
                                  febio_number(k.c), febio_number(kFebioBulkModulus)));
    } else {
      comment("    ", "fung_scale = \"none\": orthotropic elastic, the plain orthotropic StVK with the same constants");
    }
    if (fung && m.overflow == material::ExponentOverflow::kContinueLinearly) {
      note("    ", fmt::format("overflow = \"continue_linearly\" continues exp(2 Psi0/c) linearly beyond the "
                               "exponent {}; FEBio's Fung material has no cap (the same energy below it)",
                               febio_number(material::kFungExponentCap)));
    }
    out_ += fmt::format("    <material id=\"1\" name=\"flesh\" type=\"{}\">",
                        fung ? "Fung-ortho-compressible" : "orthotropic elastic");
    auto param = [&](std::string_view name, double value) {
      out_ += fmt::format("<{0}>{1}</{0}>", name, febio_number(value));
    };
    param("density", spec_.density);
    param("E1", k.E1);     // E1 = Y_t (tangent plane)
    param("E2", k.E2);     // E2 = Y_t (tangent plane, isotropic in it)
    param("E3", k.E3);     // E3 = Y_n (along the normal)
    param("G12", k.G12);   // G12 = Y_t / (2(1+ν))
    param("G23", k.G23);   // G23 = √(Y_t Y_n) / (2(1+ν))
    param("G31", k.G31);   // G31 = √(Y_t Y_n) / (2(1+ν))
    param("v12", k.nu12);  // v12 = ν (FEBio: compliance S_12 = −v12/E1)
    param("v23", k.nu23);  // v23 = ν √(Y_t/Y_n)
    param("v31", k.nu31);  // v31 = ν √(Y_n/Y_t)
    if (fung) {
      param("c", k.c);                // c = fung_scale_c: Y_t/saturation (default) or saturation·Y_t
      param("k", kFebioBulkModulus);  // FEBio requires k > 0
    }
    const Eigen::Vector3d& n = spec_.normal;
    if (n != Eigen::Vector3d::UnitZ()) {
      // FEMat3dVectorMap: axes a, b = c × a, c = a × d (normalized); with a ⟂ n and d = n × a, c = a × (n × a) = n.
      const Eigen::Vector3d a = n.unitOrthogonal();
      const Eigen::Vector3d d = n.cross(a);
      out_ += fmt::format("<mat_axis type=\"vector\"><a>{}</a><d>{}</d></mat_axis>", febio_vector(a), febio_vector(d));
    }
    out_ += "</material>\n  </Material>\n";
  }

  void mesh() {
    const MshMesh& mesh = spec_.mesh;
    // <Nodes name> defines a node set too: keep it apart from the node groups.
    std::string all = "all";
    while (mesh.node_groups.count(all) != 0) all += "_nodes";
    out_ += fmt::format("  <Mesh>\n    <Nodes name=\"{}\">\n", xml_escaped(all));
    for (Eigen::Index v = 0; v < mesh.nodes.rows(); ++v) {
      out_ += fmt::format("      <node id=\"{}\">{}</node>\n", v + 1, febio_vector(mesh.nodes.row(v).transpose()));
    }
    out_ += "    </Nodes>\n";
    std::vector<bool> used(static_cast<std::size_t>(mesh.nodes.rows()), false);
    for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
      for (int a = 0; a < 4; ++a) used[static_cast<std::size_t>(mesh.tets(e, a))] = true;
    }
    const auto unused = std::count(used.begin(), used.end(), false);
    if (unused > 0) {
      note("    ", fmt::format("{} node(s) belong to no tet; FEBio gives them no stiffness and no mass, and its "
                               "linear solve may fail",
                               unused));
    }
    comment("    ",
            "TET4G4: FEBio's four-point rule, whose mass matrix is the exact consistent one, rho V/20 (1 + "
            "delta_ab), as sflsh's; FEBio's default TET4G1 gives a rank-one element mass rho V/16 and a motion "
            "about 5 % different");
    out_ += "    <Elements type=\"TET4G4\" name=\"flesh\">\n";
    for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
      out_ += fmt::format("      <elem id=\"{}\">{},{},{},{}</elem>\n", e + 1, mesh.tets(e, 0) + 1, mesh.tets(e, 1) + 1,
                          mesh.tets(e, 2) + 1, mesh.tets(e, 3) + 1);
    }
    out_ += "    </Elements>\n";
    for (const auto& [name, nodes] : mesh.node_groups) {
      if (nodes.empty()) {
        comment("    ", fmt::format("node group '{}' is empty and left out", name));
        continue;
      }
      out_ += fmt::format("    <NodeSet name=\"{}\">{}</NodeSet>\n", xml_escaped(name), one_based_list(nodes));
    }
    out_ += "  </Mesh>\n";
  }

  void boundary() {
    constexpr std::string_view axes = "xyz";
    out_ += "  <Boundary>\n";
    for (std::size_t f = 0; f < spec_.fixes.size(); ++f) {
      const VerifyProblem::Fix& fix = spec_.fixes[f];
      out_ += fmt::format(
          "    <bc name=\"fix{}\" node_set=\"{}\" type=\"zero displacement\"><x_dof>{}</x_dof><y_dof>{}</y_dof>"
          "<z_dof>{}</z_dof></bc>\n",
          f + 1, xml_escaped(fix.group), fix.mask & 1u, (fix.mask >> 1) & 1u, (fix.mask >> 2) & 1u);
    }
    for (std::size_t k = 0; k < spec_.drives.size(); ++k) {
      const VerifyProblem::Drive& drive = spec_.drives[k];
      // A dynamic sflsh run starts from the drives' values and rates at t = 0 (model::initial_state), FEBio from
      // rest in the reference configuration.
      const ScalarDrive u = expression_drive(drive.expression);
      const double u0 = u.value(0.0), v0 = u.rate(0.0);
      if (spec_.density > 0.0 && (std::abs(u0) > 1e-12 || std::abs(v0) > 1e-9)) {
        note("    ", fmt::format("drive[{}] starts at u(0) = {:.6g} m, du/dt(0) = {:.6g} m/s: sflsh starts the "
                                 "driven nodes there, FEBio at rest with u = 0 and reaches u(t) from its first step",
                                 k + 1, u0, v0));
      }
      // u(t) = 1.0 × the load controller lc = k + 1, absolute (relative = 0).
      out_ += fmt::format(
          "    <bc name=\"drive{}\" node_set=\"{}\" type=\"prescribed displacement\"><dof>{}</dof>"
          "<value lc=\"{}\">1.0</value><relative>0</relative></bc>\n",
          k + 1, xml_escaped(drive.group), axes[static_cast<std::size_t>(drive.axis)], k + 1);
    }
    out_ += "  </Boundary>\n";
  }

  void loads() {
    if (spec_.gravity != Eigen::Vector3d::Zero()) {
      // FEElasticSolidDomain::BodyForce adds −ρ f to the residual Fext − Fint − M a: f = −g gives M a = … + ρ g.
      comment("  ", fmt::format("gravity g = ({}) m/s^2: FEBio's body force is the negative of the acceleration",
                                febio_vector(spec_.gravity)));
      out_ += fmt::format("  <Loads>\n    <body_load type=\"body force\"><force>{}</force></body_load>\n  </Loads>\n",
                          febio_vector(Eigen::Vector3d::Zero() - spec_.gravity));  // 0 − g: no "-0"
    }
    if (spec_.drives.empty()) return;
    out_ += "  <LoadData>\n";
    for (std::size_t k = 0; k < spec_.drives.size(); ++k) {
      const VerifyProblem::Drive& drive = spec_.drives[k];
      std::string febio;
      try {
        febio = febio_math_expression(drive.expression);
      } catch (const Error& err) {
        throw_error("{}: drive[{}].expression '{}' {}", spec_.file.string(), k + 1, drive.expression, err.what());
      }
      out_ += fmt::format(
          "    <load_controller id=\"{}\" name=\"drive{}\" type=\"math\"><math>{}</math></load_controller>\n", k + 1,
          k + 1, xml_escaped(febio));
    }
    out_ += "  </LoadData>\n";
  }

  void output() {
    const std::string file = fmt::format("{}_{}.txt", file_name_part(log_stem_), file_name_part(spec_.record_group));
    if (spec_.record_every > 1) {
      comment("  ", fmt::format("FEBio logs every step; sflsh's record.every = {} keeps every {}th", spec_.record_every,
                                spec_.record_every));
    }
    out_ += fmt::format(
        "  <Output>\n    <logfile><node_data data=\"ux;uy;uz\" delim=\",\" file=\"{}\" node_set=\"{}\"/></logfile>\n"
        "  </Output>\n",
        xml_escaped(file), xml_escaped(spec_.record_group));
  }
};

}  // namespace

FebioInput febio_input(const VerifyProblem& spec, std::string_view log_stem) {
  return FebioWriter(spec, log_stem).write();
}

void write_febio_input(const VerifyProblem& spec, const std::filesystem::path& path) {
  const FebioInput input = febio_input(spec, path.stem().string());
  write_text_atomically(path, input.xml);
  for (const std::string& warning : input.warnings) logger()->warn("{}: {}", path.filename().string(), warning);
  logger()->info("wrote the FEBio 4 input {} ({} nodes, {} TET4G4 elements)", path.string(), spec.mesh.nodes.rows(),
                 spec.mesh.tets.rows());
}

}  // namespace sflsh::fullspace
