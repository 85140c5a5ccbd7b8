// Output folders and atomic text files. The writers of the results live in
// src/io/output_history.cpp (history.csv) and src/io/snapshot_writer.cpp, src/io/snapshot_xdmf.cpp
// (HDF5 + XDMF snapshots).
#include "io/output.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "common/error.hpp"

namespace fdem {

namespace fs = std::filesystem;

// ------------------------------------------------------------------------------------------------
// Directories and files

void ensure_output_dir(const std::string& dir_in) {
  const std::string dir = dir_in.empty() ? std::string(".") : dir_in;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    throw InputError("cannot create output directory '" + dir + "': " + ec.message());
  }
  if (!fs::is_directory(dir, ec)) {
    throw InputError("output directory '" + dir + "' exists but is not a directory");
  }
  const std::string probe =
      (fs::path(dir) / (".fdem_write_probe_" + std::to_string(static_cast<long>(::getpid()))))
          .string();
  std::FILE* f = std::fopen(probe.c_str(), "w");
  if (!f) {
    const int err = errno;
    throw InputError("output directory '" + dir + "' is not writable: " + std::strerror(err));
  }
  const bool bad = std::fputs("probe\n", f) < 0;
  const bool close_bad = std::fclose(f) != 0;
  const int err = errno;
  std::remove(probe.c_str());
  if (bad || close_bad) {
    throw InputError("output directory '" + dir + "' is not writable: " + std::strerror(err));
  }
}

void write_file_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  auto fail = [&](const std::string& what, int err) {
    std::remove(tmp.c_str());
    throw InputError("cannot write '" + path + "' (" + what + "): " + std::strerror(err));
  };
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) {
    const int err = errno;
    throw InputError("cannot write '" + path + "' (opening " + tmp + "): " + std::strerror(err));
  }
  const size_t n = text.empty() ? 0 : std::fwrite(text.data(), 1, text.size(), f);
  if (n != text.size()) {
    const int err = errno;
    std::fclose(f);
    fail("writing " + tmp, err);
  }
  if (std::fflush(f) != 0) {
    const int err = errno;
    std::fclose(f);
    fail("flushing " + tmp, err);
  }
  if (::fsync(fileno(f)) != 0) {
    const int err = errno;
    if (err != EINVAL && err != EROFS) {  // not syncable (a pipe, a special file): go on
      std::fclose(f);
      fail("syncing " + tmp, err);
    }
  }
  if (std::fclose(f) != 0) fail("closing " + tmp, errno);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) fail("renaming " + tmp, errno);
}

}  // namespace fdem
