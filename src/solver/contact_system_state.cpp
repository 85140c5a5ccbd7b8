// ContactSystem's checkpoint (solver/contact_system.hpp, save_state and load_state): the pair
// lists with their history, the build positions, node areas and the counters of the re-check
// schedule, under "contact/".
#include "solver/contact_system.hpp"

#include <algorithm>
#include <limits>
#include <type_traits>
#include <utility>

#include "common/error.hpp"
#include "solver/state_io.hpp"

namespace fdem {

namespace {

// The pair lists' checkpoint fields (save_state and load_state): the offsets, and the used part
// (0, size) of each pair array, as f(dataset name, View).
template <int D, class F>
void visit_pairs(const PairList<D>& P, F&& f) {
  const std::pair<int, int> used(0, P.size);
  f("contact/pair_off", P.off);
  f("contact/pair_face", Kokkos::subview(P.face, used));
  f("contact/pair_fn", Kokkos::subview(P.fn, used));
  f("contact/pair_ac", Kokkos::subview(P.ac, used));
  f("contact/pair_g0", Kokkos::subview(P.g0, used));
  f("contact/pair_fs", Kokkos::subview(P.fs, used, Kokkos::ALL));
}

}  // namespace

template <int D>
template <class Self, class F>
void ContactSystem<D>::state_fields(Self& self, F&& f) {
  f("contact/xb", self.xb_);
  f("contact/node_area", self.surf_.narea);
  f("contact/may_meet", self.may_meet_);
  f("contact/need_build", self.need_build_);
  f("contact/since_check", self.since_check_);
  f("contact/builds", self.builds_);
  f("contact/handed_over", self.handed_);
  f("contact/until_recheck", self.until_recheck_);
  f("contact/stale_seen", self.stale_seen_);
}

template <int D>
void ContactSystem<D>::save_state(StateArrays& s) const {
  auto save = [&s](const char* name, const auto& x) {
    using T = std::decay_t<decltype(x)>;
    if constexpr (Kokkos::is_view<T>::value) {
      if (x.size() > 0) {
        save_view(s, name, x);
      } else if constexpr (std::is_floating_point_v<typename T::non_const_value_type>) {
        s.f64[name] = {};
      } else {
        s.i64[name] = {};
      }
    } else if constexpr (std::is_floating_point_v<T>) {
      s.put(name, x);
    } else {
      s.put_int(name, x);
    }
  };
  s.put_int("contact/pair_count", cur_.size);
  visit_pairs<D>(cur_, save);
  state_fields(*this, save);
  const ContactStatus st = read_status();
  s.put("contact/dissipated", st.dissipated);
  s.put_int("contact/active", static_cast<long long>(st.active));
  s.f64["contact/last_pass"] = {st.d2max, st.v2max, st.stale};
  s.put_int("contact/xb_all", xb_all_ ? 1 : 0);
  s.put_int("contact/list_updates", updates_);
  // for people reading the file (not read back)
  s.put_int("contact/surface_nodes", ns_);
  s.put_int("contact/active_faces", na_);
}

template <int D>
void ContactSystem<D>::load_state(const StateArrays& s, const Model<D>& m) {
  refresh_surfaces(m);  // active faces, clusters, surface nodes from m.icontact
  const long long n = s.get_int("contact/pair_count");
  if (n < 0 || n > std::numeric_limits<int>::max())
    throw InputError("checkpoint '" + s.file + "': contact/pair_count out of range");
  const int size = static_cast<int>(n);
  reserve_pairs(cur_, std::max(size, 1));
  cur_.size = size;
  auto load = [&s](const char* name, auto& x) {
    using T = std::decay_t<decltype(x)>;
    if constexpr (Kokkos::is_view<T>::value) {
      load_view(s, name, x);
    } else if constexpr (std::is_same_v<T, bool>) {
      x = s.get_int(name) != 0;
    } else if constexpr (std::is_floating_point_v<T>) {
      x = s.get(name);
    } else {
      x = static_cast<T>(s.get_int(name));
    }
  };
  visit_pairs<D>(cur_, [&load](const char* name, auto x) { load(name, x); });
  {  // the list must be one the search could have built: offsets rising to size, faces in range
    auto off = Kokkos::create_mirror_view(cur_.off);
    Kokkos::deep_copy(off, cur_.off);
    auto face = Kokkos::create_mirror_view(cur_.face);
    Kokkos::deep_copy(face, cur_.face);
    bool ok = off(0) == 0 && off(nn_) == size;
    for (int i = 0; i < nn_ && ok; ++i) ok = off(i) <= off(i + 1);
    for (int j = 0; j < size && ok; ++j) ok = face(j) >= 0 && face(j) < nf_;
    if (!ok) throw InputError("checkpoint '" + s.file + "': contact pair list is inconsistent");
  }
  ContactStatus st;
  st.dissipated = s.get("contact/dissipated");
  st.active = static_cast<double>(s.get_int("contact/active"));
  if (s.has("contact/until_recheck")) {
    state_fields(*this, load);
    const std::vector<double>& p = s.array("contact/last_pass", 3);
    st.d2max = p[0];
    st.v2max = p[1];
    st.stale = p[2];
  } else {  // checkpoints from before the re-check schedule: their lists are rebuilt at once
    auto older = [&](const char* name, auto& x) {
      if (s.has(name)) load(name, x);
    };
    state_fields(*this, older);
    need_build_ = true;
  }
  // checkpoints from before the local list updates hold build positions of surface nodes only:
  // their next handover rebuilds
  xb_all_ = s.has("contact/xb_all") && s.get_int("contact/xb_all") != 0;
  updates_ = s.has("contact/list_updates") ? static_cast<long>(s.get_int("contact/list_updates")) : 0;
  auto h = Kokkos::create_mirror_view(status_);
  h() = st;
  Kokkos::deep_copy(status_, h);
}

#define FDEM_CONTACT_STATE(D)                                     \
  template void ContactSystem<D>::save_state(StateArrays&) const; \
  template void ContactSystem<D>::load_state(const StateArrays&, const Model<D>&);
FDEM_CONTACT_STATE(2)
FDEM_CONTACT_STATE(3)
#undef FDEM_CONTACT_STATE

}  // namespace fdem
