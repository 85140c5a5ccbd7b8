// Gmsh in a child process, the transport (src/mesh/gmsh_io.cpp runs the child): the Extracted
// mesh packed into bytes and back, the pipe written and read whole, the child's captured terminal
// output cut to its last lines, its address space capped, a signal's name.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "mesh/memory_budget.hpp"
#include "mesh/mesh_internal.hpp"

namespace fdem::mesh_detail {

namespace {

void put_raw(std::string& b, const void* p, std::size_t n) {
  if (n) b.append(static_cast<const char*>(p), n);
}
template <class T>
void put(std::string& b, const T& v) {
  put_raw(b, &v, sizeof v);
}
template <class T>
void put_vec(std::string& b, const std::vector<T>& v) {
  put<std::uint64_t>(b, v.size());
  put_raw(b, v.data(), v.size() * sizeof(T));
}
void put_str(std::string& b, const std::string& s) {
  put<std::uint64_t>(b, s.size());
  put_raw(b, s.data(), s.size());
}

struct Unpacker {
  const std::string& b;
  std::size_t pos = 1;  // after the kind byte
  void raw(void* p, std::size_t n) {
    if (n > b.size() - pos) throw std::runtime_error("truncated mesh data from the Gmsh process");
    if (n) std::memcpy(p, b.data() + pos, n);
    pos += n;
  }
  template <class T>
  T get() {
    T v;
    raw(&v, sizeof v);
    return v;
  }
  std::size_t count(std::size_t elem_size) {
    const auto n = get<std::uint64_t>();
    if (n > (b.size() - pos) / elem_size) throw std::runtime_error("bad mesh data from the Gmsh process");
    return static_cast<std::size_t>(n);
  }
  template <class T>
  std::vector<T> vec() {
    std::vector<T> v(count(sizeof(T)));
    raw(v.data(), v.size() * sizeof(T));
    return v;
  }
  std::string str() {
    std::string s(count(1), '\0');
    raw(s.data(), s.size());
    return s;
  }
};

}  // namespace

void pack(std::string& b, const Extracted& ex) {
  const HostMesh& m = ex.mesh;
  put<std::int32_t>(b, m.dim);
  put_vec(b, m.X);
  put_vec(b, m.elems);
  put_vec(b, m.elem_region);
  put<std::uint64_t>(b, m.region_names.size());
  for (const auto& r : m.region_names) put_str(b, r);
  put<std::uint64_t>(b, m.node_sets.size());
  for (const auto& [name, nodes] : m.node_sets) {
    put_str(b, name);
    put_vec(b, nodes);
  }
  put<std::uint64_t>(b, m.face_sets.size());
  for (const auto& [name, faces] : m.face_sets) {
    put_str(b, name);
    put_vec(b, faces);
  }
  put_vec(b, m.ifaces);
  put_vec(b, m.iface_elems);
  put_vec(b, m.node_origin);
  std::vector<std::uint64_t> tags(ex.elem_tags.begin(), ex.elem_tags.end());
  put_vec(b, tags);
  put(b, ex.times);
}

Extracted unpack(const std::string& b) {
  Unpacker u{b};
  Extracted ex;
  HostMesh& m = ex.mesh;
  m.dim = u.get<std::int32_t>();
  m.X = u.vec<double>();
  m.elems = u.vec<int>();
  m.elem_region = u.vec<int>();
  for (std::size_t i = 0, n = u.count(8); i < n; ++i) m.region_names.push_back(u.str());
  for (std::size_t i = 0, n = u.count(16); i < n; ++i) {
    std::string name = u.str();
    m.node_sets[name] = u.vec<int>();
  }
  for (std::size_t i = 0, n = u.count(16); i < n; ++i) {
    std::string name = u.str();
    m.face_sets[name] = u.vec<int>();
  }
  m.ifaces = u.vec<int>();
  m.iface_elems = u.vec<int>();
  m.node_origin = u.vec<int>();
  const auto tags = u.vec<std::uint64_t>();
  ex.elem_tags.assign(tags.begin(), tags.end());
  ex.times = u.get<GmshTimes>();
  return ex;
}

void write_all(int fd, const std::string& b) {
  std::size_t done = 0;
  while (done < b.size()) {
    const ssize_t n = ::write(fd, b.data() + done, b.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<std::size_t>(n);
  }
}

std::string read_all(int fd) {
  std::string b;
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    b.append(buf, static_cast<std::size_t>(n));
  }
  return b;
}

// Gmsh's messages worth quoting from the child's terminal output: its Error lines and the last
// lines (what the runtime printed when it aborted), at most ~1500 characters.
std::string log_excerpt(std::FILE* log) {
  if (!log) return "";
  std::fflush(log);
  std::rewind(log);
  std::vector<std::string> lines, errors;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, log)) {
    std::string l(buf);
    while (!l.empty() && (l.back() == '\n' || l.back() == '\r')) l.pop_back();
    if (l.empty()) continue;
    if (l.find("-----") != std::string::npos || l.find("error summary") != std::string::npos) continue;
    if (l.rfind("Error", 0) == 0 && errors.size() < 3) errors.push_back(l);
    lines.push_back(l);
    if (lines.size() > 200) lines.erase(lines.begin(), lines.begin() + 100);
  }
  std::string out;
  for (const auto& e : errors) out += (out.empty() ? "" : " | ") + e;
  for (std::size_t i = lines.size() > 3 ? lines.size() - 3 : 0; i < lines.size(); ++i)
    if (std::find(errors.begin(), errors.end(), lines[i]) == errors.end())
      out += (out.empty() ? "" : " | ") + lines[i];
  if (out.size() > 1500) out = out.substr(0, 1500) + " ...";
  return out;
}

// In the child: no more address space than what is in use now plus the memory available.
void cap_address_space() {
  if (!std::isfinite(max_elements(2))) return;  // unknown, or FDEM_MEMORY_CHECK=off
  const MemoryBudget b = available_memory();
  std::ifstream st("/proc/self/status");
  std::string line;
  double vm = 0;
  while (std::getline(st, line))
    if (line.rfind("VmSize:", 0) == 0) vm = std::atof(line.c_str() + 7) * 1024.0;
  rlimit rl{};
  if (getrlimit(RLIMIT_AS, &rl) != 0) return;
  const double cap = vm + b.bytes;
  if (rl.rlim_cur == RLIM_INFINITY || cap < static_cast<double>(rl.rlim_cur)) {
    rl.rlim_cur = static_cast<rlim_t>(cap);
    setrlimit(RLIMIT_AS, &rl);
  }
}

std::string signal_name(int sig) {
  switch (sig) {
    case SIGABRT:
      return "SIGABRT";
    case SIGSEGV:
      return "SIGSEGV";
    case SIGKILL:
      return "SIGKILL";
    case SIGBUS:
      return "SIGBUS";
    case SIGFPE:
      return "SIGFPE";
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "signal " + std::to_string(sig);
  }
}

}  // namespace fdem::mesh_detail
