#pragma once
// Files and folders of the tests that run the `fdem` program or read what it wrote: one copy of
// the small helpers every such test file needs.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace fdem::test {

// The whole file as bytes ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A fresh (removed, not created) folder fdem_<tag>_<name>_<pid> in the temporary directory.
inline std::string scratch_dir(const std::string& tag, const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() /
                 ("fdem_" + tag + "_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  return d.string();
}

// Exit status of `sh -c cmd` by std::system; 128 + signal when a signal ended it.
inline int system_status(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  if (WIFEXITED(rc)) return WEXITSTATUS(rc);
  return WIFSIGNALED(rc) ? 128 + WTERMSIG(rc) : -1;
}

// history.csv as columns by name.
inline std::map<std::string, std::vector<double>> read_history(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::getline(f, line);
  std::vector<std::string> names;
  {
    std::stringstream ss(line);
    std::string x;
    while (std::getline(ss, x, ',')) names.push_back(x);
  }
  std::map<std::string, std::vector<double>> cols;
  while (std::getline(f, line)) {
    std::stringstream ss(line);
    std::string x;
    for (size_t k = 0; k < names.size() && std::getline(ss, x, ','); ++k)
      cols[names[k]].push_back(std::stod(x));
  }
  return cols;
}

}  // namespace fdem::test
