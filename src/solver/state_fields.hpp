#pragma once
// The two walks over one list of checkpoint fields (Simulation::checkpoint_fields): StateSaver
// puts every field into a StateArrays, StateLoader reads every field back (sizes checked: an
// InputError names the checkpoint). A field is
//   real(name, double&), integer(name, I&)                     one value;
//   values(name, n, get, set)                                  n doubles (get() -> container,
//                                                              set(const std::vector<double>&));
//   view(name, view, present)                                  a device View (solver/state_io.hpp),
//                                                              only where `present`.
// optional = true: older checkpoints may lack the entry (it is then left as it is on loading).
#include <string>
#include <vector>

#include "io/checkpoint.hpp"
#include "solver/state_io.hpp"

namespace fdem {

class StateSaver {
 public:
  explicit StateSaver(StateArrays& s) : s_(s) {}
  void real(const std::string& name, double x, bool /*optional*/ = false) { s_.put(name, x); }
  template <class I>
  void integer(const std::string& name, I x, bool /*optional*/ = false) {
    s_.put_int(name, static_cast<long long>(x));
  }
  template <class Get, class Set>
  void values(const std::string& name, long long /*n*/, Get get, Set /*set*/, bool /*optional*/ = false) {
    const auto v = get();
    s_.f64[name] = std::vector<double>(v.begin(), v.end());
  }
  template <class V>
  void view(const std::string& name, const V& v, bool present = true) {
    if (present) save_view(s_, name, v);
  }

 private:
  StateArrays& s_;
};

class StateLoader {
 public:
  explicit StateLoader(const StateArrays& s) : s_(s) {}
  void real(const std::string& name, double& x, bool optional = false) {
    if (!optional || s_.has(name)) x = s_.get(name);
  }
  template <class I>
  void integer(const std::string& name, I& x, bool optional = false) {
    if (!optional || s_.has(name)) x = static_cast<I>(s_.get_int(name));
  }
  template <class Get, class Set>
  void values(const std::string& name, long long n, Get /*get*/, Set set, bool optional = false) {
    if (!optional || s_.has(name)) set(s_.array(name, n));
  }
  template <class V>
  void view(const std::string& name, const V& v, bool present = true) {
    if (present) load_view(s_, name, v);
  }

 private:
  const StateArrays& s_;
};

}  // namespace fdem
