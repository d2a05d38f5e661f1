// muparser drive expressions in the syntax of FEBio's math parser (febio_export.hpp: febio_math_expression).
//
// muparser 2.3 (the drives' parser, verify_problem.cpp) and FEBio 4's expression parser (the one its 'math' load
// controller uses) share + − * / ^, parentheses, numbers, pi, e and
// most functions, but differ in:
//   - `^`: right-associative in muparser (2^3^2 = 2^9), left-associative in FEBio; both bind a leading minus
//     looser than `^` (−2^2 = −4). Every power operand that is not a number, name, call or parenthesis is
//     parenthesized here, so both read the same tree.
//   - names: muparser's log is ln (FEBio: ln), log10 is FEBio's log; FEBio's sgn(0) = 1 where muparser's
//     sign(0) = 0; FEBio lacks log2, sum, asinh, atanh, rint; unary + is a syntax error in FEBio.
//   - FEBio has no ?:, comparisons, && or ||, and copies the expression into a 512-byte buffer.
// The expression is parsed with muparser's grammar and written back with FEBio's spelling.
#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/febio_export.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace sflsh::fullspace {

namespace {

/// How tightly a piece of FEBio text binds, loosest first: a sum needs parentheses as a factor, a product as a
/// divisor, a negation as an operand of `^` or of a binary operator's right side, a power as an operand of `^`.
enum class FebioBinding { kSum, kProduct, kNegation, kPower, kAtom };

/// A translated subexpression.
struct FebioPiece {
  std::string text;
  FebioBinding binding = FebioBinding::kAtom;
};

/// `piece` as an operand that must bind at least as tightly as `min` (a negation never stands unparenthesized
/// right of a binary operator or under `^`: FEBio would parse it, but the reader should not have to).
std::string febio_operand(const FebioPiece& piece, FebioBinding min) {
  if (piece.binding >= min && piece.binding != FebioBinding::kNegation) return piece.text;
  if (piece.binding == FebioBinding::kNegation && min <= FebioBinding::kSum) return piece.text;
  return "(" + piece.text + ")";
}

/// muparser's built-in functions that FEBio has under the same name (FEBio 4's function table).
constexpr std::string_view kSameName[] = {"sin",   "cos", "tan",  "asin", "acos", "atan", "sinh", "cosh",  "tanh",
                                          "acosh", "exp", "sqrt", "abs",  "min",  "max",  "avg",  "atan2", "ln"};

/// muparser's operators that FEBio lacks, in order of first appearance, each named once.
std::vector<std::string> operators_febio_lacks(std::string_view s) {
  std::vector<std::string> found;
  auto add = [&](std::string what) {
    if (std::find(found.begin(), found.end(), what) == found.end()) found.push_back(std::move(what));
  };
  int depth = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::string two(s.substr(i, 2));
    if (two == "<=" || two == ">=" || two == "==" || two == "!=") {
      add("the comparison operator " + two);
      ++i;
    } else if (two == "&&" || two == "||") {
      add("the logical operator " + two);
      ++i;
    } else if (two == "+=" || two == "-=" || two == "*=" || two == "/=") {
      add("an assignment (" + two + ")");
      ++i;
    } else if (s[i] == '<' || s[i] == '>') {
      add(std::string("the comparison operator ") + s[i]);
    } else if (s[i] == '?' || s[i] == ':') {
      add("the conditional operator ?:");
    } else if (s[i] == '=') {
      add("an assignment (=)");
    } else if (s[i] == '(') {
      ++depth;
    } else if (s[i] == ')') {
      --depth;
    } else if (s[i] == ',' && depth == 0) {
      add("several comma-separated expressions");
    }
  }
  return found;
}

class MuparserToFebio {
 public:
  explicit MuparserToFebio(std::string_view expression) : s_(expression) {}

  std::string translate() {
    const std::vector<std::string> lacking = operators_febio_lacks(s_);
    if (!lacking.empty()) {
      std::string list = lacking.front();
      for (std::size_t k = 1; k < lacking.size(); ++k) list += (k + 1 == lacking.size() ? " and " : ", ") + lacking[k];
      throw_error("uses {}, which FEBio's math parser lacks", list);
    }
    const FebioPiece whole = sum();
    skip_space();
    if (pos_ < s_.size()) refuse_token();
    return whole.text;
  }

 private:
  std::string_view s_;
  std::size_t pos_ = 0;

  void skip_space() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_])) != 0) ++pos_;
  }

  /// The next character after blanks (0 at the end).
  char peek() {
    skip_space();
    return pos_ < s_.size() ? s_[pos_] : '\0';
  }

  /// A token that cannot continue the expression (only input muparser itself refuses, which
  /// load_verify_problem has ruled out, gets here: operators_febio_lacks catches the rest first).
  [[noreturn]] void refuse_token() {
    throw_error("cannot be translated for FEBio: unexpected '{}' at position {}", s_.substr(pos_, 1), pos_ + 1);
  }

  /// sum := product (('+' | '−') product)*
  FebioPiece sum() {
    FebioPiece left = product();
    for (char op = peek(); (op == '+' || op == '-') && !assignment_ahead(); op = peek()) {
      ++pos_;
      const FebioPiece right = product();
      left = {febio_operand(left, FebioBinding::kSum) + op + febio_operand(right, FebioBinding::kProduct),
              FebioBinding::kSum};
    }
    return left;
  }

  /// product := signed (('*' | '/') signed)*
  FebioPiece product() {
    FebioPiece left = signed_power();
    for (char op = peek(); (op == '*' || op == '/') && !assignment_ahead(); op = peek()) {
      ++pos_;
      const FebioPiece right = signed_power();
      left = {febio_operand(left, FebioBinding::kProduct) + op + febio_operand(right, FebioBinding::kPower),
              FebioBinding::kProduct};
    }
    return left;
  }

  /// "+=" and the like: the operator character followed by '='.
  bool assignment_ahead() const { return pos_ + 1 < s_.size() && s_[pos_ + 1] == '='; }

  /// signed := ('−' | '+') signed | power — muparser's sign binds looser than ^ (−2^2 = −4), as FEBio's does.
  FebioPiece signed_power() {
    const char c = peek();
    if (c == '+') {  // FEBio has no unary plus
      ++pos_;
      return signed_power();
    }
    if (c == '-') {
      ++pos_;
      const FebioPiece inner = signed_power();
      return {"-" + febio_operand(inner, FebioBinding::kPower), FebioBinding::kNegation};
    }
    return power();
  }

  /// power := primary ('^' signed)? — right-associative (muparser); both operands parenthesized unless atomic,
  /// since FEBio's ^ is left-associative.
  FebioPiece power() {
    const FebioPiece base = primary();
    if (peek() != '^') return base;
    ++pos_;
    const FebioPiece exponent = signed_power();
    return {febio_operand(base, FebioBinding::kAtom) + "^" + febio_operand(exponent, FebioBinding::kAtom),
            FebioBinding::kPower};
  }

  FebioPiece primary() {
    const char c = peek();
    if (c == '(') {
      ++pos_;
      const FebioPiece inner = sum();
      expect(')');
      return inner;  // parentheses are put back where FEBio needs them
    }
    if (std::isdigit(static_cast<unsigned char>(c)) != 0 || c == '.') return {number(), FebioBinding::kAtom};
    if (std::isalpha(static_cast<unsigned char>(c)) != 0 || c == '_') {
      const std::string name = identifier();
      if (peek() == '(') {
        ++pos_;
        return call(name);
      }
      if (name == "t") return {"t", FebioBinding::kAtom};
      if (name == "pi" || name == "_pi") return {"pi", FebioBinding::kAtom};  // FEBio's constant pi
      if (name == "e" || name == "_e") return {"e", FebioBinding::kAtom};     // FEBio's constant e = exp(1)
      throw_error("uses the name '{}', which FEBio's math controller does not define (it knows t, pi, e)", name);
    }
    if (c == '\0') throw_error("cannot be translated for FEBio: it ends early");
    refuse_token();
  }

  void expect(char c) {
    if (peek() != c) {
      if (pos_ >= s_.size()) throw_error("cannot be translated for FEBio: '{}' expected at the end", c);
      refuse_token();
    }
    ++pos_;
  }

  /// A decimal literal as muparser reads it (digits, optional fraction, optional exponent), kept verbatim:
  /// FEBio reads it with atof, which gives the same double.
  std::string number() {
    const std::size_t start = pos_;
    auto digits = [&] {
      while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_])) != 0) ++pos_;
    };
    digits();
    if (pos_ < s_.size() && s_[pos_] == '.') {
      ++pos_;
      digits();
    }
    if (pos_ < s_.size() && (s_[pos_] == 'e' || s_[pos_] == 'E')) {
      const std::size_t mark = pos_++;
      if (pos_ < s_.size() && (s_[pos_] == '+' || s_[pos_] == '-')) ++pos_;
      const std::size_t exponent = pos_;
      digits();
      if (pos_ == exponent) pos_ = mark;  // "2e" is not an exponent (muparser refuses it anyway)
    }
    return std::string(s_.substr(start, pos_ - start));
  }

  std::string identifier() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) != 0 || s_[pos_] == '_')) ++pos_;
    return std::string(s_.substr(start, pos_ - start));
  }

  /// The arguments of a call, after its '(' up to and including ')'.
  std::vector<FebioPiece> arguments() {
    std::vector<FebioPiece> args;
    if (peek() == ')') {
      ++pos_;
      return args;
    }
    args.push_back(sum());
    while (peek() == ',') {
      ++pos_;
      args.push_back(sum());
    }
    expect(')');
    return args;
  }

  FebioPiece call(const std::string& name) {
    if (name == "asinh" || name == "atanh" || name == "rint")
      throw_error("uses the function {}, which FEBio's math parser lacks", name);
    const std::vector<FebioPiece> args = arguments();
    auto list = [&] {
      std::string out;
      for (const FebioPiece& a : args) {
        if (!out.empty()) out += ',';
        out += a.text;
      }
      return out;
    };
    for (const std::string_view same : kSameName) {
      if (name == same) return {name + "(" + list() + ")", FebioBinding::kAtom};
    }
    if (args.size() == 1) {
      const std::string& x = args[0].text;
      if (name == "log") return {"ln(" + x + ")", FebioBinding::kAtom};     // muparser's log is the natural logarithm
      if (name == "log10") return {"log(" + x + ")", FebioBinding::kAtom};  // FEBio's log is base 10
      if (name == "log2") return {"(ln(" + x + ")/ln(2))", FebioBinding::kAtom};
      // FEBio's H(x) is 1, ½, 0 for x >, =, < 0, so H(x) − H(−x) is muparser's sign (FEBio's sgn(0) is 1).
      if (name == "sign")
        return {"(H(" + x + ")-H(-" + febio_operand(args[0], FebioBinding::kPower) + "))", FebioBinding::kAtom};
    }
    if (name == "sum" && !args.empty()) {
      std::string out = args[0].text;
      for (std::size_t k = 1; k < args.size(); ++k) out += "+" + febio_operand(args[k], FebioBinding::kProduct);
      return {"(" + out + ")", FebioBinding::kAtom};
    }
    throw_error("uses the function {} with {} argument(s), which FEBio's math parser lacks", name, args.size());
  }
};

}  // namespace

std::string febio_math_expression(std::string_view expression) {
  std::string febio = MuparserToFebio(expression).translate();
  // FEBio 4's parser reads at most 511 characters of an expression.
  constexpr std::size_t kFebioMaxLength = 511;
  if (febio.size() > kFebioMaxLength) {
    throw_error("is {} characters long in FEBio's syntax, more than FEBio's math parser reads ({})", febio.size(),
                kFebioMaxLength);
  }
  return febio;
}

}  // namespace sflsh::fullspace
