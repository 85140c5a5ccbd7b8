#pragma once
// Copies of device Views into and out of checkpoint state (io/checkpoint.hpp), in logical index
// order (row-major over the View's extents), so a checkpoint does not depend on the backend's
// memory layout.
#include <string>
#include <type_traits>

#include "kernels/fdem_kokkos.hpp"
#include "io/checkpoint.hpp"

namespace fdem {

namespace state_detail {
template <class H, class F>
void for_each_index(const H& h, F&& f) {
  constexpr int r = static_cast<int>(H::rank);
  static_assert(r >= 0 && r <= 3, "views of rank 0 to 3");
  if constexpr (r == 0) {
    f(h());
  } else if constexpr (r == 1) {
    for (size_t i = 0; i < h.extent(0); ++i) f(h(i));
  } else if constexpr (r == 2) {
    for (size_t i = 0; i < h.extent(0); ++i)
      for (size_t j = 0; j < h.extent(1); ++j) f(h(i, j));
  } else {
    for (size_t i = 0; i < h.extent(0); ++i)
      for (size_t j = 0; j < h.extent(1); ++j)
        for (size_t k = 0; k < h.extent(2); ++k) f(h(i, j, k));
  }
}
}  // namespace state_detail

// Saves all of `v` (doubles into s.f64, integers into s.i64) under `name`.
template <class V>
void save_view(StateArrays& s, const std::string& name, const V& v) {
  auto h = Kokkos::create_mirror_view(v);
  Kokkos::deep_copy(h, v);
  using T = typename V::non_const_value_type;
  if constexpr (std::is_floating_point_v<T>) {
    auto& out = s.f64[name];
    out.clear();
    out.reserve(h.size());
    state_detail::for_each_index(h, [&](const T& x) { out.push_back(x); });
  } else {
    auto& out = s.i64[name];
    out.clear();
    out.reserve(h.size());
    state_detail::for_each_index(h, [&](const T& x) { out.push_back(static_cast<long long>(x)); });
  }
}

// Fills all of `v` from the entry `name`, which must have exactly v.size() values (else
// InputError naming the checkpoint).
template <class V>
void load_view(const StateArrays& s, const std::string& name, const V& v) {
  auto h = Kokkos::create_mirror_view(v);
  using T = typename V::non_const_value_type;
  size_t n = 0;
  const long long want = static_cast<long long>(v.size());
  if constexpr (std::is_floating_point_v<T>) {
    const auto& in = s.array(name, want);
    state_detail::for_each_index(h, [&](T& x) {
      x = in[n++];
    });
  } else {
    const auto& in = s.int_array(name, want);
    state_detail::for_each_index(h, [&](T& x) {
      x = static_cast<T>(in[n++]);
    });
  }
  Kokkos::deep_copy(v, h);
}

}  // namespace fdem
