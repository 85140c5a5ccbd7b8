#pragma once
// Parameters and expressions of a case file (docs/case-format.md): "parameters": {"rate": 0.05};
// a string value "=expr" anywhere else is replaced by the value of expr (numbers, parameter names,
// pi, + - * /, parentheses). Internal to the case reader (src/io/case.cpp).
#include <map>
#include <string>

#include "io/json_reader.hpp"

namespace fdem::case_detail {

using Params = std::map<std::string, double>;

// The "parameters" object of the document (absent: none). Names must be identifiers, values finite
// numbers; failures throw InputError naming the key path.
Params read_parameters(json& doc, const Reader& R);

// The value of the expression `s` ("=..."; the '=' is skipped). Errors name `path`, the expression
// and the parameters there are.
double eval_expression(const std::string& s, const Params& params, const Reader& R,
                       const std::string& path);

// Replaces every string "=expr" under `j` (at key path `path`) by its value, except in the top-level
// "parameters" object.
void substitute(json& j, const std::string& path, const Params& params, const Reader& R);

}  // namespace fdem::case_detail
