// libFuzzer target: case reader. Input = case file text, optionally followed by a NUL byte and
// --set overrides, one per line. Runs both entry points:
//   load_case(file, overrides)             (the CLI path: text parser, duplicate keys, file checks)
//   parse_case(json::parse(text), overrides)   (in-memory document)
// and serialises the resolved case (as `fdem run` does). fdem::InputError is the only allowed
// failure; any other exception, crash, sanitizer report, hang or huge allocation is a bug.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "fuzz_common.hpp"
#include "io/case.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const size_t nul = input.find('\0');
  const std::string text = input.substr(0, nul);
  std::vector<std::string> overrides;
  if (nul != std::string::npos) {
    size_t start = nul + 1;
    while (start <= input.size() && overrides.size() < 8) {
      size_t end = input.find('\n', start);
      if (end == std::string::npos) end = input.size();
      overrides.push_back(input.substr(start, end - start));
      start = end + 1;
    }
  }

  const std::string path = fdem_fuzz::write_temp("case.json", text.data(), text.size());
  try {
    fdem::Case c = fdem::load_case(path, overrides);
    (void)c.resolved.dump(2);
  } catch (const fdem::InputError&) {
  } catch (...) {
    fdem_fuzz::unexpected("load_case");
  }

  nlohmann::json doc = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false,
                                             /*ignore_comments=*/true);
  if (doc.is_discarded()) return 0;
  try {
    fdem::Case c = fdem::parse_case(std::move(doc), "fuzz.json", overrides);
    (void)c.resolved.dump(2);
  } catch (const fdem::InputError&) {
  } catch (...) {
    fdem_fuzz::unexpected("parse_case");
  }
  return 0;
}
