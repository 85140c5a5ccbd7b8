#pragma once
// Host orchestration of a run: case -> mesh -> interfaces -> device model -> time loop -> output.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace fdem {

struct RunOptions {
  std::string out_dir;                // default: ./out/<case name>
  std::vector<std::string> overrides;  // --set key.path=value
  bool progress = true;               // progress line on a terminal / periodic lines in logs
};

// Runs a case; returns the summary written to out_dir/summary.json. Throws InputError (bad input)
// or NumericalError (instability), both with a clear message.
nlohmann::json run_case(const std::string& case_path, const RunOptions& opt);

// Validates a case file and its mesh without running it; returns a short report (counts, mesh
// quality, stable time step). Throws InputError.
nlohmann::json check_case(const std::string& case_path, const std::vector<std::string>& overrides);

}  // namespace fdem
