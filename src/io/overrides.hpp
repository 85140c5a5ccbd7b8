#pragma once
// `--set key.path=value` overrides of a case (docs/case-format.md). Internal to the case reader
// (src/io/case.cpp).
#include <string>

#include "io/json_reader.hpp"

namespace fdem::case_detail {

// Sets doc[key.path] = value ("key.path=value"; value parsed as JSON when it parses, else taken as
// a string). Objects and array elements on the path must exist, the last key may be new. Throws
// InputError naming the override.
void apply_override(json& doc, const std::string& ov, const Reader& R);

// Null members of objects are the same as absent ones (so --set key=null removes an option).
void strip_nulls(json& j);

}  // namespace fdem::case_detail
