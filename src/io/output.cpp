// Output folders and atomic text files. The writers of the results live in
// src/io/output_history.cpp (history.csv) and src/io/snapshot_writer.cpp, src/io/snapshot_xdmf.cpp
// (HDF5 + XDMF snapshots).
#include "io/output.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

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

// ------------------------------------------------------------------------------------------------
// What a run owns in its folder

const std::vector<std::string>& output_file_names() {
  static const std::vector<std::string> names = {
      "case.json",     "case.json.tmp",        "summary.json",   "summary.json.tmp",
      "history.csv",   "history.csv.tmp",      "fragments.csv",  "fragments.csv.tmp",
      "snapshots.h5",  "snapshots.h5.damaged", "snapshots.xdmf", "snapshots.xdmf.tmp",
      "checkpoint.h5", "checkpoint.h5.tmp",    "bodies.csv",     "bodies.csv.tmp"};
  return names;
}

std::vector<std::string> remove_old_outputs(const std::string& dir) {
  std::vector<std::string> removed;
  for (const auto& name : output_file_names()) {
    const fs::path p = fs::path(dir) / name;
    std::error_code ec;
    if (!fs::is_regular_file(fs::symlink_status(p, ec))) continue;  // a link, a folder: not ours
    if (!fs::remove(p, ec) || ec)
      throw InputError("cannot remove '" + p.string() + "', a result of an earlier run in the output folder" +
                       (ec ? ": " + ec.message() : std::string()));
    removed.push_back(name);
  }
  return removed;
}

void refuse_inputs_among_outputs(const std::string& dir, const std::vector<std::string>& inputs) {
  for (const auto& name : output_file_names()) {
    const fs::path p = fs::path(dir) / name;
    for (const auto& in : inputs) {
      std::error_code ec;
      if (in.empty() || !fs::equivalent(p, in, ec) || ec) continue;
      throw InputError("the output folder '" + dir + "' is where the input file '" + in +
                       "' is, under the name '" + name + "' that fdem writes its results to; give " +
                       "another folder with --out (input files are never written to)");
    }
  }
}

OutputLock::OutputLock(const std::string& dir_in) {
  const std::string dir = dir_in.empty() ? std::string(".") : dir_in;
  const std::string path = (fs::path(dir) / kName).string();
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    const int err = errno;
    throw InputError("cannot create the lock file '" + path +
                     "' of the output folder: " + std::strerror(err));
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char buf[32] = {};
    const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
    std::string pid = n > 0 ? std::string(buf, static_cast<size_t>(n)) : std::string();
    while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK || err == EINTR)
      throw InputError("the output folder '" + dir + "' is in use by another fdem run (pid " +
                       (pid.empty() ? std::string("unknown") : pid) + ", lock file " + path +
                       "); wait for it to end or give another folder with --out");
    // a file system without flock (some network file systems): go on unlocked
    std::fprintf(stderr,
                 "fdem: warning: cannot lock the output folder '%s' (%s); another run "
                 "writing there at the same time would mix its results with this one's\n",
                 dir.c_str(), std::strerror(err));
    return;
  }
  const std::string pid = std::to_string(static_cast<long>(::getpid())) + "\n";
  // (for the message of a second run only: a failure to write it changes nothing)
  if (::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t w = ::pwrite(fd_, pid.data(), pid.size(), 0);
  }
}

OutputLock::~OutputLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock; the file stays (removing it would race)
}

}  // namespace fdem
