#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>

#include <toml++/toml.h>

#include <cmath>
#include <sstream>

namespace sflsh::body {

namespace {

std::string where(const std::filesystem::path& path, const toml::node& node) {
  return fmt::format("{}:{}", path.string(), node.source().begin.line);
}

std::string string_field(const std::filesystem::path& path, const toml::table& t, const char* key, bool required) {
  const toml::node* node = t.get(key);
  if (!node) {
    require(!required, "{}: subject is missing field '{}'", where(path, t), key);
    return {};
  }
  const auto value = node->value<std::string>();
  require(value.has_value(), "{}: field '{}' must be a string", where(path, *node), key);
  return *value;
}

}  // namespace

std::vector<Subject> load_subjects(const std::filesystem::path& path) {
  require(std::filesystem::exists(path), "{}: subjects file not found", path.string());
  toml::table root;
  try {
    root = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    throw_error("{}:{}: {}", path.string(), e.source().begin.line, e.description());
  }
  std::vector<Subject> subjects;
  for (const auto& [key, node] : root) {
    require(key.str() == "subject", "{}: unknown key '{}' (expected [[subject]] tables)", where(path, node), key.str());
  }
  const toml::array* list = root["subject"].as_array();
  require(list != nullptr, "{}: no [[subject]] tables", path.string());
  for (const toml::node& item : *list) {
    const toml::table* t = item.as_table();
    require(t != nullptr, "{}: 'subject' must be an array of tables", where(path, item));
    for (const auto& [k, v] : *t) {
      const std::string ks(k.str());
      require(ks == "name" || ks == "split" || ks == "body" || ks == "description" || ks == "beta",
              "{}: unknown field '{}' (expected name, split, body, description, beta)", where(path, v), ks);
    }
    Subject s;
    s.name = string_field(path, *t, "name", true);
    s.split = string_field(path, *t, "split", true);
    s.body = string_field(path, *t, "body", false);
    s.description = string_field(path, *t, "description", false);
    require(s.split == "train" || s.split == "test", "{}: subject '{}' has split '{}', expected train or test",
            where(path, *t), s.name, s.split);
    const toml::array* beta = (*t)["beta"].as_array();
    require(beta != nullptr, "{}: subject '{}' needs beta = [10 numbers]", where(path, *t), s.name);
    require(beta->size() == kNumBetas, "{}: subject '{}' has {} beta values, expected {}", where(path, *beta), s.name,
            beta->size(), kNumBetas);
    for (std::size_t i = 0; i < beta->size(); ++i) {
      const auto v = (*beta)[i].value<double>();
      require(v.has_value() && std::isfinite(*v), "{}: subject '{}' beta[{}] is not a finite number",
              where(path, (*beta)[i]), s.name, i);
      s.beta(static_cast<Eigen::Index>(i)) = *v;
    }
    for (const Subject& other : subjects)
      require(other.name != s.name, "{}: duplicate subject name '{}'", where(path, *t), s.name);
    subjects.push_back(std::move(s));
  }
  return subjects;
}

void save_subjects(const std::filesystem::path& path, const std::vector<Subject>& subjects, const std::string& header) {
  std::ostringstream out;
  std::istringstream lines(header);
  for (std::string line; std::getline(lines, line);) out << "# " << line << "\n";
  for (const Subject& s : subjects) {
    out << "\n[[subject]]\n";
    out << "name = " << toml::value<std::string>(s.name) << "\n";
    out << "split = " << toml::value<std::string>(s.split) << "\n";
    if (!s.body.empty()) out << "body = " << toml::value<std::string>(s.body) << "\n";
    if (!s.description.empty()) out << "description = " << toml::value<std::string>(s.description) << "\n";
    out << "beta = [";
    for (int i = 0; i < kNumBetas; ++i) out << (i ? ", " : "") << fmt::format("{:.4f}", s.beta(i));
    out << "]\n";
  }
  write_text_atomically(path, out.str());
}

std::vector<Subject> default_subjects() {
  std::vector<Subject> all = load_subjects(data_dir() / "subjects.toml");
  const auto open = data_dir() / "open_body_subjects.toml";
  if (std::filesystem::exists(open)) {
    for (Subject& s : load_subjects(open)) all.push_back(std::move(s));
  }
  return all;
}

const Subject& find_subject(const std::vector<Subject>& subjects, const std::string& name) {
  std::string known;
  for (const Subject& s : subjects) {
    if (s.name == name) return s;
    known += (known.empty() ? "" : ", ") + s.name;
  }
  throw_error("unknown subject '{}' (known: {})", name, known);
}

Betas parse_betas(const std::string& text) {
  std::string cleaned = text;
  for (char& c : cleaned)
    if (c == ',' || c == '[' || c == ']') c = ' ';
  std::istringstream in(cleaned);
  Betas beta = Betas::Zero();
  int count = 0;
  std::string token;
  while (in >> token) {
    require(count < kNumBetas, "--betas: more than {} values in \"{}\"", kNumBetas, text);
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    require(used == token.size() && std::isfinite(value), "--betas: '{}' is not a number (in \"{}\")", token, text);
    beta(count++) = value;
  }
  require(count > 0, "--betas: expected up to {} numbers, got \"{}\"", kNumBetas, text);
  return beta;
}

}  // namespace sflsh::body
