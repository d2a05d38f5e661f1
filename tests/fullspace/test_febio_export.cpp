// `sflsh verify --export-febio`: the driven block written as a FEBio 4 input against the input FEBio 4.11 ran
// (tests/data/febio_export/example_block_fung_tet4g4.feb), the material variants, muparser → FEBio expressions,
// refusals, and the command line.
#include "error_of.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_file.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/febio_export.hpp>
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/fullspace/verify_problem.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace sflsh::fullspace {
namespace {

namespace fs = std::filesystem;
using sflsh::testing::error_of;
using sflsh::testing::run_sflsh;
using sflsh::testing::scratch_dir;
using sflsh::testing::text_of;
using sflsh::testing::write_text;

#ifdef SFLSH_TEST_DATA_DIR
const fs::path kFebioExportData = fs::path(SFLSH_TEST_DATA_DIR) / "febio_export";
#else
const fs::path kFebioExportData = fs::path(__FILE__).parent_path().parent_path() / "data" / "febio_export";
#endif

/// An XML element as far as these tests read .feb files: name, attributes, character data, children.
struct FebXml {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::string text;
  std::vector<FebXml> children;

  /// The first child called `child_name` (an empty element, and a test failure, when there is none).
  const FebXml& child(const std::string& child_name) const {
    for (const FebXml& c : children) {
      if (c.name == child_name) return c;
    }
    ADD_FAILURE() << "<" << name << "> has no <" << child_name << ">";
    static const FebXml none;
    return none;
  }
  std::vector<const FebXml*> all(const std::string& child_name) const {
    std::vector<const FebXml*> out;
    for (const FebXml& c : children) {
      if (c.name == child_name) out.push_back(&c);
    }
    return out;
  }
  double number() const { return std::stod(text); }
};

/// A minimal reader for the .feb files here: elements, double-quoted attributes, text, comments, <?…?>.
class FebXmlReader {
 public:
  explicit FebXmlReader(std::string text) : s_(std::move(text)) {}

  FebXml document() {
    skip_misc();
    return element();
  }

 private:
  std::string s_;
  std::size_t pos_ = 0;

  bool at(const char* token) const { return s_.compare(pos_, std::char_traits<char>::length(token), token) == 0; }
  void skip_to(const char* token) { pos_ = s_.find(token, pos_) + std::char_traits<char>::length(token); }
  void skip_misc() {
    for (;;) {
      while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_])) != 0) ++pos_;
      if (at("<?")) {
        skip_to("?>");
      } else if (at("<!--")) {
        skip_to("-->");
      } else {
        return;
      }
    }
  }
  static std::string decoded(std::string t) {
    const std::array<std::pair<std::string, std::string>, 5> entities = {
        {{"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&apos;", "'"}, {"&amp;", "&"}}};
    for (const auto& [entity, c] : entities) {
      for (std::size_t k = t.find(entity); k != std::string::npos; k = t.find(entity, k + 1))
        t.replace(k, entity.size(), c);
    }
    return t;
  }
  std::string name_token() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() && std::string_view(" \t\r\n/>=").find(s_[pos_]) == std::string_view::npos) ++pos_;
    return s_.substr(start, pos_ - start);
  }
  FebXml element() {
    FebXml e;
    ++pos_;  // '<'
    e.name = name_token();
    for (;;) {
      while (std::isspace(static_cast<unsigned char>(s_[pos_])) != 0) ++pos_;
      if (at("/>")) {
        pos_ += 2;
        return e;
      }
      if (at(">")) break;
      const std::string key = name_token();
      pos_ += 2;  // ="
      const std::size_t end = s_.find('"', pos_);
      e.attributes[key] = decoded(s_.substr(pos_, end - pos_));
      pos_ = end + 1;
    }
    ++pos_;  // '>'
    for (;;) {
      if (at("</")) {
        skip_to(">");
        e.text = decoded(e.text);
        return e;
      }
      if (at("<!--")) {
        skip_to("-->");
      } else if (at("<")) {
        e.children.push_back(element());
      } else {
        e.text += s_[pos_++];
      }
    }
  }
};

FebXml read_feb(const std::string& text) { return FebXmlReader(text).document(); }

std::vector<double> comma_numbers(const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(std::stod(cell));
  return out;
}

/// A node set's content, as 1-based ids.
std::set<int> id_set(const std::string& text) {
  std::set<int> out;
  for (const double v : comma_numbers(text)) out.insert(static_cast<int>(v));
  return out;
}

/// The content of the node set called `name` in <Mesh>.
std::set<int> node_set(const FebXml& feb, const std::string& name) {
  for (const FebXml* s : feb.child("Mesh").all("NodeSet")) {
    if (s->attributes.at("name") == name) return id_set(s->text);
  }
  ADD_FAILURE() << "no NodeSet " << name;
  return {};
}

/// The FEBio block of the example: 10 × 10 × 3 cells, bone = zmin (x, y held, z driven), top = zmax.
std::string febio_block_toml(const std::string& material_extra = "",
                             const std::string& expression = "0.0025*(1-cos(4*pi*t))^2",
                             const std::string& top_extra = "mass = \"consistent\"\n",
                             const std::string& integrator = "newmark") {
  return "mesh = \"block.msh\"\ndensity = 1000.0\n" + top_extra +
         "\n[material]\nyoung_tangent = 5000.0\nyoung_normal = 2000.0\npoisson = 0.2\nsaturation = 4.0\n" +
         material_extra + "\n[[fix]]\ngroup = \"zmin\"\ncomponents = \"xy\"\n\n[[drive]]\ngroup = \"zmin\"\n" +
         "component = \"z\"\nexpression = \"" + expression +
         "\"\n\n[time]\nduration = 1.0\nstep = 0.0010416666666666667\nintegrator = \"" + integrator +
         "\"\n\n[record]\ngroup = \"zmax\"\nevery = 16\n";
}

/// Writes the block mesh and a problem file into `dir` and loads it.
VerifyProblem febio_block_problem(const fs::path& dir, const std::string& toml) {
  const MshMesh mesh = box_tet_mesh(Eigen::Vector3d(0.1, 0.1, 0.03), {10, 10, 3});
  write_msh(dir / "block.msh", mesh.nodes, mesh.tets, mesh.node_groups);
  write_text(dir / "problem.toml", toml);
  return load_verify_problem(dir / "problem.toml");
}

/// Node coordinates by 1-based id.
std::map<int, Eigen::Vector3d> feb_nodes(const FebXml& feb) {
  std::map<int, Eigen::Vector3d> out;
  for (const FebXml* n : feb.child("Mesh").child("Nodes").all("node")) {
    const std::vector<double> x = comma_numbers(n->text);
    out[std::stoi(n->attributes.at("id"))] = Eigen::Vector3d(x.at(0), x.at(1), x.at(2));
  }
  return out;
}

/// The elements as sorted node-id quadruples; every one must have positive volume in FEBio's tet4 order.
std::set<std::array<int, 4>> feb_tets(const FebXml& feb) {
  const std::map<int, Eigen::Vector3d> x = feb_nodes(feb);
  std::set<std::array<int, 4>> out;
  for (const FebXml* e : feb.child("Mesh").child("Elements").all("elem")) {
    const std::vector<double> v = comma_numbers(e->text);
    std::array<int, 4> q{};
    for (std::size_t a = 0; a < 4; ++a) q[a] = static_cast<int>(v.at(a));
    const Eigen::Vector3d x0 = x.at(q[0]);
    const double volume6 = (x.at(q[1]) - x0).dot((x.at(q[2]) - x0).cross(x.at(q[3]) - x0));
    EXPECT_GT(volume6, 0.0) << "element " << e->attributes.at("id");
    std::sort(q.begin(), q.end());
    out.insert(q);
  }
  return out;
}

/// The load controller's expression of the bc's `value lc`, evaluated with muparser.
ScalarDrive controller_of(const FebXml& feb, const FebXml& bc) {
  const std::string lc = bc.child("value").attributes.at("lc");
  for (const FebXml* c : feb.child("LoadData").all("load_controller")) {
    if (c->attributes.at("id") == lc) {
      EXPECT_EQ(c->attributes.at("type"), "math");
      return expression_drive(c->child("math").text);
    }
  }
  ADD_FAILURE() << "no load controller " << lc;
  return expression_drive("0");
}

TEST(FebioExport, DrivenBlockMatchesTheInputFebioRan) {
  const fs::path dir = scratch_dir();
  const FebioInput input = febio_input(febio_block_problem(dir, febio_block_toml()), "e");
  EXPECT_TRUE(input.warnings.empty()) << input.warnings.front();
  const FebXml ours = read_feb(input.xml);
  const FebXml ref = read_feb(text_of(kFebioExportData / "example_block_fung_tet4g4.feb"));
  ASSERT_EQ(ours.name, "febio_spec");
  EXPECT_EQ(ours.attributes.at("version"), "4.0");
  EXPECT_EQ(ours.child("Module").attributes.at("type"), "solid");

  const FebXml& control = ours.child("Control");
  const FebXml& ref_control = ref.child("Control");
  for (const char* key : {"analysis", "time_steps", "plot_level"})
    EXPECT_EQ(control.child(key).text, ref_control.child(key).text) << key;
  EXPECT_NEAR(control.child("step_size").number(), ref_control.child("step_size").number(), 1e-15 / 960.0);
  const FebXml& solver = control.child("solver");
  EXPECT_EQ(solver.child("symmetric_stiffness").text, "symmetric");
  for (const char* key : {"max_refs", "dtol", "etol", "rtol", "lstol"})
    EXPECT_EQ(solver.child(key).number(), ref_control.child("solver").child(key).number()) << key;
  EXPECT_EQ(solver.child("qn_method").child("max_ups").text, "0");
  EXPECT_EQ(solver.child("beta").number(), 0.25);
  EXPECT_EQ(solver.child("gamma").number(), 0.5);

  const FebXml& material = ours.child("Material").child("material");
  const FebXml& ref_material = ref.child("Material").child("material");
  EXPECT_EQ(material.attributes.at("type"), "Fung-ortho-compressible");
  EXPECT_EQ(material.attributes.at("type"), ref_material.attributes.at("type"));
  ASSERT_EQ(material.children.size(), ref_material.children.size());  // no mat_axis: the normal is +z
  for (const FebXml& p : ref_material.children) {
    const double expected = p.number();
    EXPECT_NEAR(material.child(p.name).number(), expected, 1e-12 * std::abs(expected)) << p.name;
  }

  const std::map<int, Eigen::Vector3d> nodes = feb_nodes(ours), ref_nodes = feb_nodes(ref);
  ASSERT_EQ(nodes.size(), ref_nodes.size());
  for (const auto& [id, x] : ref_nodes) EXPECT_LT((nodes.at(id) - x).norm(), 1e-15) << "node " << id;
  EXPECT_EQ(ours.child("Mesh").child("Elements").attributes.at("type"), "TET4G4");
  EXPECT_EQ(feb_tets(ours), feb_tets(ref));
  // Our groups are zmin / zmax, the example's bone / top: the same nodes.
  EXPECT_EQ(node_set(ours, "zmin"), node_set(ref, "bone"));
  EXPECT_EQ(node_set(ours, "zmax"), node_set(ref, "top"));
  EXPECT_EQ(ours.child("MeshDomains").child("SolidDomain").attributes,
            ref.child("MeshDomains").child("SolidDomain").attributes);

  const std::vector<const FebXml*> bcs = ours.child("Boundary").all("bc"), ref_bcs = ref.child("Boundary").all("bc");
  ASSERT_EQ(bcs.size(), 2u);
  ASSERT_EQ(ref_bcs.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const FebXml &bc = *bcs[k], &ref_bc = *ref_bcs[k];
    EXPECT_EQ(bc.attributes.at("type"), ref_bc.attributes.at("type"));
    EXPECT_EQ(node_set(ours, bc.attributes.at("node_set")), node_set(ref, ref_bc.attributes.at("node_set")));
    for (const FebXml& p : ref_bc.children) {
      if (p.name != "value") {
        EXPECT_EQ(bc.child(p.name).text, p.text) << p.name;
      }
    }
  }
  const FebXml& drive = *bcs[1];
  EXPECT_EQ(drive.child("value").number(), ref_bcs[1]->child("value").number());
  const ScalarDrive u = controller_of(ours, drive), ref_u = controller_of(ref, *ref_bcs[1]);
  for (const double t : {0.0, 0.05, 0.125, 0.3, 0.5, 0.71, 1.0}) EXPECT_NEAR(u.value(t), ref_u.value(t), 1e-15) << t;

  const FebXml& log = ours.child("Output").child("logfile").child("node_data");
  const FebXml& ref_log = ref.child("Output").child("logfile").child("node_data");
  EXPECT_EQ(log.attributes.at("data"), ref_log.attributes.at("data"));
  EXPECT_EQ(log.attributes.at("delim"), ref_log.attributes.at("delim"));
  EXPECT_EQ(log.attributes.at("file"), "e_zmax.txt");
  EXPECT_EQ(node_set(ours, log.attributes.at("node_set")), node_set(ref, ref_log.attributes.at("node_set")));
}

TEST(FebioExport, FungScaleNoneIsOrthotropicElastic) {
  const fs::path dir = scratch_dir();
  const FebXml feb =
      read_feb(febio_input(febio_block_problem(dir, febio_block_toml("fung_scale = \"none\"\n")), "b").xml);
  const FebXml& material = feb.child("Material").child("material");
  EXPECT_EQ(material.attributes.at("type"), "orthotropic elastic");
  EXPECT_TRUE(material.all("c").empty());
  EXPECT_TRUE(material.all("k").empty());
  EXPECT_EQ(material.child("E3").number(), 2000.0);
  EXPECT_NEAR(material.child("G23").number(), std::sqrt(5000.0 * 2000.0) / 2.4, 1e-12 * 2000.0);
  EXPECT_NEAR(material.child("v31").number(), 0.2 * std::sqrt(2000.0 / 5000.0), 1e-15);
}

TEST(FebioExport, TiltedNormalGivesAMaterialAxisWhoseThirdAxisIsTheNormal) {
  const fs::path dir = scratch_dir();
  const FebXml feb =
      read_feb(febio_input(febio_block_problem(dir, febio_block_toml("normal = [1.0, -2.0, 0.5]\n")), "n").xml);
  const FebXml& axis = feb.child("Material").child("material").child("mat_axis");
  EXPECT_EQ(axis.attributes.at("type"), "vector");
  const std::vector<double> a = comma_numbers(axis.child("a").text), d = comma_numbers(axis.child("d").text);
  // FEMat3dVectorMap: the third axis is a × d, normalized.
  const Eigen::Vector3d third =
      Eigen::Vector3d(a.at(0), a.at(1), a.at(2)).cross(Eigen::Vector3d(d.at(0), d.at(1), d.at(2)));
  EXPECT_LT((third.normalized() - Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).norm(), 1e-14);
}

TEST(FebioExport, DifferencesFebioCannotReproduceAreCommentsAndWarnings) {
  const fs::path dir = scratch_dir();
  const std::string toml = febio_block_toml("overflow = \"continue_linearly\"\n", "0.001*sin(2*pi*t)+0.002",
                                            "mass = \"lumped\"\ngravity = [0.0, 0.0, -9.81]\n", "bdf2");
  const FebioInput input = febio_input(febio_block_problem(dir, toml), "w");
  EXPECT_EQ(input.warnings.size(), 4u);  // lumped mass, BDF2, the Fung cap, a drive not starting at rest
  for (const std::string& w : input.warnings) {
    EXPECT_EQ(w.find('\n'), std::string::npos);
    EXPECT_NE(input.xml.find(w.substr(0, 30)), std::string::npos) << w;  // also an XML comment
  }
  const FebXml feb = read_feb(input.xml);
  const FebXml& body = feb.child("Loads").child("body_load");
  EXPECT_EQ(body.attributes.at("type"), "body force");
  EXPECT_EQ(comma_numbers(body.child("force").text), (std::vector<double>{0.0, 0.0, 9.81}));  // FEBio's f = −g
  for (std::size_t at = input.xml.find("<!--"); at != std::string::npos; at = input.xml.find("<!--", at + 4)) {
    const std::size_t end = input.xml.find("-->", at + 4);
    ASSERT_NE(end, std::string::npos);
    EXPECT_EQ(input.xml.substr(at + 4, end - at - 4).find("--"), std::string::npos);  // XML forbids "--" in comments
  }
}

TEST(FebioExport, StaticProblemIsAStaticAnalysis) {
  const fs::path dir = scratch_dir();
  std::string toml = febio_block_toml("", "0.001*t", "", "backward_euler");
  toml.replace(toml.find("density = 1000.0"), 16, "density = 0.0");
  const FebioInput input = febio_input(febio_block_problem(dir, toml), "s");
  const FebXml feb = read_feb(input.xml);
  EXPECT_EQ(feb.child("Control").child("analysis").text, "STATIC");
  EXPECT_TRUE(feb.child("Control").child("solver").all("beta").empty());
  EXPECT_TRUE(input.warnings.empty());
}

TEST(FebioExport, ExpressionsAreTranslatedOrRefused) {
  // Read back by muparser, the FEBio text must give the original values (the parentheses make it the same tree
  // under both grammars).
  for (const char* e : {"2^3^t", "-t^2", "(-t)^2", "2^-t", "2*-t^2", "t--1", "+t", "-(t-1)*3/4/(t+1)",
                        "0.0025*(1-cos(4*pi*t))^2", "1.5e-3*exp(-t)*sin(_pi*t)", "sum(t,1,t^2)", "ln(t+1)+_e"}) {
    const std::string febio = febio_math_expression(e);
    for (const double t : {0.3, 1.7})
      EXPECT_NEAR(expression_drive(febio).value(t), expression_drive(e).value(t), 1e-14) << e << " -> " << febio;
  }
  EXPECT_EQ(febio_math_expression("2^3^2"), "2^(3^2)");  // muparser's ^ is right-associative, FEBio's left
  EXPECT_EQ(febio_math_expression("-2^2"), "-2^2");      // −4 in both
  EXPECT_EQ(febio_math_expression("log(t)+log10(t)+log2(t)"), "ln(t)+log(t)+(ln(t)/ln(2))");
  EXPECT_EQ(febio_math_expression("sign(t-1)"), "(H(t-1)-H(-(t-1)))");
  EXPECT_EQ(febio_math_expression(" 0.0025 * ( 1 - cos(4*pi*t) ) ^ 2 "), "0.0025*(1-cos(4*pi*t))^2");
  for (const auto& [e, construct] :
       std::vector<std::pair<std::string, std::string>>{{"t<0.5 ? t : 0.5", "conditional operator"},
                                                        {"(t>0.5)*t", "comparison operator >"},
                                                        {"t<=1", "comparison operator <="},
                                                        {"(t>0)&&(t<1)", "logical operator &&"},
                                                        {"asinh(t)", "function asinh"},
                                                        {"rint(t)", "function rint"}}) {
    EXPECT_NE(error_of([&] { febio_math_expression(e); }).find(construct), std::string::npos) << e;
  }
  std::string long_expression = "t";
  for (int k = 0; k < 300; ++k) long_expression += "+t";
  EXPECT_NE(error_of([&] { febio_math_expression(long_expression); }).find("511"), std::string::npos);
}

TEST(FebioExport, UnparsableDriveIsAOneLineErrorAndNoFile) {
  const fs::path dir = scratch_dir();
  const VerifyProblem spec = febio_block_problem(dir, febio_block_toml("", "t<0.5 ? 0.01*t : 0.005"));
  const std::string message = error_of([&] { write_febio_input(spec, dir / "x.feb"); });
  EXPECT_NE(message.find("problem.toml"), std::string::npos) << message;
  EXPECT_NE(message.find("drive[1]"), std::string::npos) << message;
  EXPECT_NE(message.find("conditional operator ?:"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "x.feb"));
}

TEST(FebioExport, CommandLineWritesOnlyTheFebFileWithoutOut) {
  const fs::path dir = scratch_dir();
  febio_block_problem(dir, febio_block_toml());
  std::set<fs::path> before;
  for (const auto& e : fs::directory_iterator(dir)) before.insert(e.path());
  const auto r = run_sflsh(
      "verify " + (dir / "problem.toml").string() + " --export-febio " + (dir / "block.feb").string() + " -q", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::set<fs::path> after;
  for (const auto& e : fs::directory_iterator(dir)) after.insert(e.path());
  before.insert(dir / "block.feb");
  EXPECT_EQ(after, before);  // the .feb file and nothing else
  const FebXml feb = read_feb(text_of(dir / "block.feb"));
  EXPECT_EQ(feb.child("Output").child("logfile").child("node_data").attributes.at("file"), "block_zmax.txt");
  EXPECT_EQ(feb_tets(feb).size(), 1800u);

  const auto none = run_sflsh("verify " + (dir / "problem.toml").string(), dir);
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("--out DIR or --export-febio FILE.feb"), std::string::npos) << none.err;
  EXPECT_EQ(std::count(none.err.begin(), none.err.end(), '\n'), 1) << none.err;

  write_text(dir / "bad.toml", febio_block_toml("", "t>0.5"));
  const auto bad =
      run_sflsh("verify " + (dir / "bad.toml").string() + " --export-febio " + (dir / "bad.feb").string(), dir);
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("comparison operator >"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "bad.feb"));
}

TEST(FebioExport, CommandLineWithOutAlsoSolves) {
  const fs::path dir = scratch_dir();
  const MshMesh mesh = box_tet_mesh(Eigen::Vector3d(0.1, 0.02, 0.02), {2, 1, 1});
  write_msh(dir / "block.msh", mesh.nodes, mesh.tets, mesh.node_groups);
  std::string toml = febio_block_toml("", "0.001*t", "", "backward_euler");
  toml.replace(toml.find("duration = 1.0"), 14, "duration = 0.0020833333333333333");
  write_text(dir / "problem.toml", toml);
  const auto r = run_sflsh("verify " + (dir / "problem.toml").string() + " --out " + (dir / "out").string() +
                               " --no-vtk --export-febio " + (dir / "bar.feb").string() + " -q",
                           dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "bar.feb"));
  EXPECT_TRUE(fs::exists(dir / "out" / "history.csv"));
}

}  // namespace
}  // namespace sflsh::fullspace
