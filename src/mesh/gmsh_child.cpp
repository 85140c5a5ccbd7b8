// Gmsh in a child process (run_gmsh_isolated, gmsh_internal.hpp): the fork; the child's side (its
// terminal output captured in a temporary file, its address space capped, the Gmsh session, its
// answer through a pipe); the parent's side (the answer read, the child reaped, its errors and its
// death turned into InputError, the session's times recorded); and the transport between them (the
// Extracted mesh packed into bytes and back, the pipe written and read whole, the captured output
// cut to its last lines, a signal's name). One concern: a Gmsh session that cannot take this
// process down. The session itself is in gmsh_io.cpp.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <functional>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "common/setup_times.hpp"
#include "mesh/gmsh_internal.hpp"
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

// ---- Gmsh in a child process ----
// Gmsh can abort the whole process: an error thrown inside its OpenMP regions ends in
// std::terminate (a .geo surface of zero area), and an assertion or an allocation failure in a
// mesher does the same. So every Gmsh session runs in a forked child: it meshes, turns the model
// into an Extracted, and sends that (or an error message) back through a pipe; its terminal output
// (Gmsh's Info/Warning/Error lines, and what the C++ runtime prints when it aborts) goes to an
// unlinked temporary file. The parent reads the pipe, reaps the child and, if the child died,
// reports the signal with Gmsh's last messages as an InputError. The child's address space is
// capped at the memory available (memory_budget.hpp), so that a mesh too large for the machine
// stops Gmsh instead of the machine. Cost: one fork and a copy of the mesh through the pipe
// (docs/developing.md, "Refusals").

// Gmsh is one global state: one session at a time in this process (run_gmsh_isolated holds it).
std::mutex& gmsh_mutex() {
  static std::mutex m;
  return m;
}

// The Gmsh session's times into the set-up phases: its meshing, extraction and the rest (the
// child process, the copy of the mesh through the pipe) of `total` wall / cpu seconds.
void record_gmsh_times(const GmshTimes& t, double total_wall, double total_cpu) {
  if (t.trial[0] > 0) setup_times::add("gmsh_trial_meshes", t.trial[0], t.trial[1]);
  setup_times::add("gmsh_meshing", t.mesh[0], t.mesh[1]);
  setup_times::add("gmsh_extraction", t.extract[0], t.extract[1]);
  setup_times::add("gmsh_process", std::max(0.0, total_wall - t.trial[0] - t.mesh[0] - t.extract[0]),
                   std::max(0.0, total_cpu - t.trial[1] - t.mesh[1] - t.extract[1]));
}

// When the session started (after the lock): wall clock and this process's CPU seconds.
struct SessionStart {
  std::chrono::steady_clock::time_point wall0;
  double cpu0;
};

// A pipe (fds: read end, write end) and a fork: the child's pid in the parent, 0 in the child; -1
// (the pipe closed) when either fails.
pid_t fork_with_pipe(int (&fds)[2]) {
  pid_t pid = -1;
  if (::pipe(fds) == 0) {
    pid = ::fork();
    if (pid < 0) {
      ::close(fds[0]);
      ::close(fds[1]);
    }
  }
  return pid;
}

// No child could be made: work() in a Gmsh session in this process.
Extracted run_in_this_process(std::FILE* log, const SessionStart& start,
                              const std::function<Extracted()>& work) {
  if (log) std::fclose(log);
  GmshSession session(false);
  Extracted ex = work();
  record_gmsh_times(ex.times,
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - start.wall0).count(),
                    setup_times::process_cpu_seconds() - start.cpu0);
  return ex;
}

// The child: its terminal output into `log`, its address space capped, work() in a Gmsh session,
// and "M" with the packed mesh, "E" with an InputError's message or "X" with another error
// through the pipe. Never returns, never runs the parent's exit handlers.
[[noreturn]] void run_child(const int (&fds)[2], std::FILE* log, const std::string& source,
                            const std::string& doing, const std::function<Extracted()>& work) {
  ::close(fds[0]);
  if (log) {
    ::dup2(::fileno(log), 1);
    ::dup2(::fileno(log), 2);
    std::setvbuf(stdout, nullptr, _IONBF, 0);
    std::setvbuf(stderr, nullptr, _IONBF, 0);
  }
  cap_address_space();
  std::string out;
  try {
    Extracted ex;
    {
      GmshSession session(log != nullptr);
      ex = work();
    }
    out = "M";
    pack(out, ex);
  } catch (const InputError& e) {
    out = std::string("E") + e.what();
  } catch (const std::bad_alloc&) {
    out = "E" + source + ": Gmsh ran out of memory while trying to " + doing + " (" +
          std::to_string(available_memory().bytes / 1073741824.0) + " GiB available)";
  } catch (const std::exception& e) {
    out = std::string("X") + e.what();
  } catch (...) {
    out = "Xunknown error";
  }
  write_all(fds[1], out);
  ::close(fds[1]);
  ::_exit(0);
}

// The parent: reads the child's answer to the end, reaps the child and returns its mesh; its
// error, or its death (the signal or exit status, the memory it used and Gmsh's last messages),
// becomes InputError naming `source`.
Extracted wait_for_child(pid_t pid, const int (&fds)[2], std::FILE* log, const SessionStart& start,
                         const std::string& source, const std::string& doing) {
  ::close(fds[1]);
  const std::string data = read_all(fds[0]);
  ::close(fds[0]);
  int status = 0;
  rusage ru{};
  while (::wait4(pid, &status, 0, &ru) < 0 && errno == EINTR) {
  }
  const std::string excerpt = log_excerpt(log);
  if (log) std::fclose(log);
  setup_times::note_gmsh_peak(static_cast<double>(ru.ru_maxrss) * 1024.0);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0 && !data.empty()) {
    if (data[0] == 'E') throw InputError(data.substr(1));
    if (data[0] == 'X') throw InputError(source + ": Gmsh could not " + doing + ": " + data.substr(1));
    if (data[0] == 'M') {
      Extracted ex = unpack(data);
      record_gmsh_times(ex.times,
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start.wall0).count(),
                        setup_times::process_cpu_seconds() - start.cpu0);  // the child's CPU time included
      return ex;
    }
  }
  std::string how = WIFSIGNALED(status) ? "was killed by " + signal_name(WTERMSIG(status))
                                        : "exited with status " + std::to_string(WEXITSTATUS(status));
  char mem[96];
  std::snprintf(mem, sizeof mem, " after using %.3g GiB (%.3g GiB available)",
                static_cast<double>(ru.ru_maxrss) / 1048576.0, available_memory().bytes / 1073741824.0);
  throw InputError(source + ": Gmsh failed while trying to " + doing + ": the meshing process " + how + mem +
                   (excerpt.empty() ? std::string() : "; Gmsh's last messages: " + excerpt));
}

}  // namespace

// Phases: the lock and the start of the clocks, the fork, then the child's side and the parent's
// (or, without a child, the session in this process).
Extracted run_gmsh_isolated(const std::string& source, const std::string& doing,
                            const std::function<Extracted()>& work) {
  std::lock_guard<std::mutex> lock(gmsh_mutex());
  const SessionStart start{std::chrono::steady_clock::now(), setup_times::process_cpu_seconds()};
  std::fflush(nullptr);
  std::FILE* log = std::tmpfile();
  int fds[2];
  const pid_t pid = fork_with_pipe(fds);
  if (pid < 0) return run_in_this_process(log, start, work);
  if (pid == 0) run_child(fds, log, source, doing, work);
  return wait_for_child(pid, fds, log, start, source, doing);
}

}  // namespace fdem::mesh_detail
