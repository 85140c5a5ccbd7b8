#pragma once
// Shared helpers of the fuzz targets.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

namespace fdem_fuzz {

// A private folder for this fuzzing process, removed at exit.
struct WorkDir {
  std::string path;
  WorkDir()
      : path((std::filesystem::temp_directory_path() / ("fdem_fuzz_" + std::to_string(::getpid())))
                 .string()) {
    std::filesystem::create_directories(path);
  }
  ~WorkDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

inline const std::string& work_dir() {
  static const WorkDir dir;
  return dir.path;
}

inline std::string write_temp(const std::string& name, const char* data, size_t size) {
  const std::string path = work_dir() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data, static_cast<std::streamsize>(size));
  out.close();
  if (!out) {
    std::fprintf(stderr, "fuzz harness: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

// Any exception other than fdem::InputError escaping a reader is a bug: say which, then crash.
[[noreturn]] inline void unexpected(const char* where) {
  try {
    throw;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\n%s: unexpected exception (not InputError): %s\n", where, e.what());
  } catch (const std::string& s) {
    std::fprintf(stderr, "\n%s: unexpected std::string thrown: %s\n", where, s.c_str());
  } catch (...) {
    std::fprintf(stderr, "\n%s: unexpected exception of unknown type\n", where);
  }
  std::abort();
}

}  // namespace fdem_fuzz
