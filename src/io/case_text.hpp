#pragma once
// Text helpers of the case reader (src/io/case.cpp): number formatting, lists, key paths and the
// "did you mean" suggestions of its messages. Internal to the reader; not part of io/case.hpp.
#include <cstddef>
#include <string>
#include <vector>

namespace fdem::case_detail {

constexpr double kPi = 3.14159265358979323846;

// "%.6g" of v.
std::string fmt_num(double v);

std::string join(const std::vector<std::string>& v, const char* sep = ", ");

// "'a', 'b'" (sorted unless sort is false), or "none".
std::string quoted_list(std::vector<std::string> v, bool sort = true);

// Key path of a member ("time" + "end_time" -> "time.end_time") or an array element.
std::string child(const std::string& path, const std::string& key);
std::string child(const std::string& path, size_t i);

// The nearest of `candidates` to `key` (known aliases first, then edit distance, then prefix), or ""
// if none is close.
std::string suggest(const std::string& key, const std::vector<std::string>& candidates);

// "; did you mean 'x'?" for the suggestion, or "" if there is none.
std::string did_you_mean(const std::string& key, const std::vector<std::string>& candidates);

// A name used as a reference: non-empty, letters, digits, '_', '-', '.'.
bool valid_name(const std::string& s);

}  // namespace fdem::case_detail
