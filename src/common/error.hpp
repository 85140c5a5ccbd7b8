#pragma once
// Error types shared by the whole program. Exit statuses (see src/app/main.cpp):
//   InputError     -> 2  (bad case file, bad mesh, bad command line)
//   NumericalError -> 3  (non-finite state, energy blow-up, inverted element during a run)
#include <stdexcept>
#include <string>

namespace fdem {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct NumericalError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace fdem
