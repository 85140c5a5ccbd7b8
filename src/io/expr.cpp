// Expressions of a case file: a recursive-descent evaluator over numbers, parameters, pi,
// + - * /, parentheses and the functions of `call` (sqrt, sin, min, pow, ...).
#include "io/expr.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace fdem::case_detail {
namespace {

class Expr {
 public:
  Expr(const std::string& s, const std::map<std::string, double>& params, const Reader& R,
       const std::string& path)
      : s_(s), params_(params), R_(R), path_(path) {}

  double eval() {
    pos_ = 1;  // skip '='
    double v = sum();
    skip();
    if (pos_ != s_.size()) error("unexpected '" + s_.substr(pos_, 1) + "'");
    if (!std::isfinite(v)) error("the result is not finite (division by zero?)");
    return v;
  }

 private:
  [[noreturn]] void error(const std::string& why) const {
    std::vector<std::string> names;
    for (const auto& kv : params_) names.push_back(kv.first);
    const std::string shown = s_.size() > 80 ? s_.substr(0, 77) + "..." : s_;
    R_.fail(path_, "expression '" + shown + "': " + why + " (expressions use numbers, parameters (" +
                       (names.empty() ? std::string("none defined") : join(names)) +
                       "), pi, + - * /, parentheses and the functions " + functions() + ")");
  }
  void skip() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  double sum() {
    double v = product();
    while (true) {
      skip();
      if (pos_ < s_.size() && (s_[pos_] == '+' || s_[pos_] == '-')) {
        char op = s_[pos_++];
        double w = product();
        v = op == '+' ? v + w : v - w;
      } else {
        return v;
      }
    }
  }
  double product() {
    double v = unary();
    while (true) {
      skip();
      if (pos_ < s_.size() && (s_[pos_] == '*' || s_[pos_] == '/')) {
        char op = s_[pos_++];
        double w = unary();
        v = op == '*' ? v * w : v / w;
      } else {
        return v;
      }
    }
  }
  double unary() {
    skip();
    if (pos_ < s_.size() && (s_[pos_] == '-' || s_[pos_] == '+')) {
      char op = s_[pos_++];
      Nest nest(*this);
      double v = unary();
      return op == '-' ? -v : v;
    }
    return primary();
  }
  // Recursion guard: "=((((...1...))))" or "=------1" nested without limit would overflow the stack.
  struct Nest {
    explicit Nest(Expr& e) : e_(e) {
      if (++e_.depth_ > 100) e_.error("nested more than 100 levels deep");
    }
    ~Nest() { --e_.depth_; }
    Expr& e_;
  };
  double primary() {
    skip();
    if (pos_ >= s_.size()) error("unexpected end");
    char ch = s_[pos_];
    if (ch == '(') {
      ++pos_;
      Nest nest(*this);
      double v = sum();
      skip();
      if (pos_ >= s_.size() || s_[pos_] != ')') error("missing ')'");
      ++pos_;
      return v;
    }
    if (std::isdigit(static_cast<unsigned char>(ch)) || ch == '.') {
      const char* begin = s_.c_str() + pos_;
      char* end = nullptr;
      double v = std::strtod(begin, &end);
      if (end == begin) error("bad number");
      pos_ += static_cast<size_t>(end - begin);
      return v;
    }
    if (std::isalpha(static_cast<unsigned char>(ch)) || ch == '_') {
      size_t start = pos_;
      while (pos_ < s_.size() &&
             (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
        ++pos_;
      std::string name = s_.substr(start, pos_ - start);
      skip();
      if (pos_ < s_.size() && s_[pos_] == '(') return call(name);
      auto it = params_.find(name);
      if (it != params_.end()) return it->second;
      if (name == "pi") return kPi;
      std::vector<std::string> names;
      for (const auto& kv : params_) names.push_back(kv.first);
      error("unknown parameter '" + name + "'" + did_you_mean(name, names));
    }
    error("unexpected '" + std::string(1, ch) + "'");
  }

  static std::string functions() {
    return "sqrt, abs, exp, log, log10, sin, cos, tan, asin, acos, atan (one argument; angles in "
           "radians), atan2, pow, min, max (two)";
  }
  // name(args...) at '(': one of the functions above, its arguments separated by commas.
  double call(const std::string& name) {
    ++pos_;  // '('
    Nest nest(*this);
    std::vector<double> a;
    while (true) {
      a.push_back(sum());
      skip();
      if (pos_ < s_.size() && s_[pos_] == ',') {
        ++pos_;
        continue;
      }
      if (pos_ >= s_.size() || s_[pos_] != ')') error("missing ')' after the arguments of " + name);
      ++pos_;
      break;
    }
    static const std::map<std::string, double (*)(double)> one = {
        {"sqrt", [](double x) { return std::sqrt(x); }},   {"abs", [](double x) { return std::fabs(x); }},
        {"exp", [](double x) { return std::exp(x); }},     {"log", [](double x) { return std::log(x); }},
        {"log10", [](double x) { return std::log10(x); }}, {"sin", [](double x) { return std::sin(x); }},
        {"cos", [](double x) { return std::cos(x); }},     {"tan", [](double x) { return std::tan(x); }},
        {"asin", [](double x) { return std::asin(x); }},   {"acos", [](double x) { return std::acos(x); }},
        {"atan", [](double x) { return std::atan(x); }}};
    static const std::map<std::string, double (*)(double, double)> two = {
        {"atan2", [](double y, double x) { return std::atan2(y, x); }},
        {"pow", [](double x, double y) { return std::pow(x, y); }},
        {"min", [](double x, double y) { return std::min(x, y); }},
        {"max", [](double x, double y) { return std::max(x, y); }}};
    double v;
    if (one.count(name)) {
      if (a.size() != 1) error(name + " takes one argument (got " + std::to_string(a.size()) + ")");
      v = one.at(name)(a[0]);
    } else if (two.count(name)) {
      if (a.size() != 2) error(name + " takes two arguments (got " + std::to_string(a.size()) + ")");
      v = two.at(name)(a[0], a[1]);
    } else {
      std::vector<std::string> names;
      for (const auto& kv : one) names.push_back(kv.first);
      for (const auto& kv : two) names.push_back(kv.first);
      error("unknown function '" + name + "'" + did_you_mean(name, names));
    }
    if (!std::isfinite(v)) error(name + " is not defined there (the result is not a finite number)");
    return v;
  }

  const std::string& s_;
  const std::map<std::string, double>& params_;
  const Reader& R_;
  std::string path_;
  size_t pos_ = 0;
  int depth_ = 0;
};


}  // namespace

Params read_parameters(json& doc, const Reader& R) {
  Params params;
  if (!doc.contains("parameters")) return params;
  json& pj = doc["parameters"];
  R.require_object(pj, "parameters");
  for (auto it = pj.begin(); it != pj.end(); ++it) {
    const std::string p = child("parameters", it.key());
    const std::string& k = it.key();
    bool ident = !k.empty() && (std::isalpha(static_cast<unsigned char>(k[0])) || k[0] == '_') &&
                 std::all_of(k.begin(), k.end(), [](char ch) {
                   return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_';
                 });
    if (!ident)
      R.fail(p, "'" + k + "' is not a valid parameter name (allowed: letters, digits, '_', not starting "
                          "with a digit)");
    params[k] = R.number_value(*it, p, any());
  }
  return params;
}

double eval_expression(const std::string& s, const Params& params, const Reader& R,
                       const std::string& path) {
  return Expr(s, params, R, path).eval();
}

void substitute(json& j, const std::string& path, const Params& params, const Reader& R) {
  if (j.is_string()) {
    const std::string& s = j.get_ref<const std::string&>();
    if (!s.empty() && s[0] == '=') {
      std::string copy = s;
      j = Expr(copy, params, R, path).eval();
    }
  } else if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (path.empty() && it.key() == "parameters") continue;
      substitute(it.value(), child(path, it.key()), params, R);
    }
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i) substitute(j[i], child(path, i), params, R);
  }
}

}  // namespace fdem::case_detail
