// ContactSystem's checkpoint (solver/contact_system.hpp, save_state and load_state): the pair
// lists with their history, the build positions, node areas (by node id) and the counters of the re-check
// schedule, under "contact/"; and the pairs with a history in whole-mesh numbering, from which a
// part of a run over another number of processes (or one process) takes its own.
#include "solver/contact_system.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <unordered_map>
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

// ContactSystem::load_pair_rows's phases: the own nodes and the held faces by whole-mesh ids; the
// rows of own nodes whose face this process holds; in the order of a search; into the lists.

// Whole-mesh id -> own node (the first nown nodes; ids empty: one process, the ids are the nodes).
std::unordered_map<long long, int> own_node_index(int nown, const std::vector<int>& ids) {
  std::unordered_map<long long, int> node;
  for (int i = 0; i < nown; ++i) node.emplace(ids.empty() ? i : ids[static_cast<size_t>(i)], i);
  return node;
}

// Every face's nodes on the host, D per face (a copy made when asked).
template <int D>
std::vector<int> face_node_table(const FaceNodes<D>& F) {
  const auto outer = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), F.outer);
  const auto iface = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), F.iface);
  std::vector<int> t(static_cast<size_t>(F.nf) * D);
  for (int f = 0; f < F.nf; ++f)
    for (int a = 0; a < D; ++a) t[static_cast<size_t>(f) * D + a] = face_node_of<D>(outer, iface, F.nb, f, a);
  return t;
}

// Sorted whole-mesh vertex ids -> face.
template <int D>
using FaceIndex = std::map<std::array<long long, D>, int>;

template <int D>
FaceIndex<D> face_index(const FaceNodes<D>& faces, const std::vector<int>& ids) {
  const std::vector<int> fnode = face_node_table<D>(faces);
  FaceIndex<D> face_of;
  for (int f = 0; f < faces.nf; ++f) {
    std::array<long long, D> key;
    for (int k = 0; k < D; ++k) {
      const int v = fnode[static_cast<size_t>(f) * D + k];
      key[k] = ids.empty() ? v : ids[static_cast<size_t>(v)];
    }
    std::sort(key.begin(), key.end());
    face_of.emplace(key, f);
  }
  return face_of;
}

// A row of "contact/pairs" this process takes: its own node, the face's place in a search's order
// (its owner element with the pair filter, else 0), the face, and the row.
struct SavedPair {
  int node, order, face;
  size_t row;
};

// The rows of the own nodes whose face this process holds (the others' faces dropped, with a note).
template <int D>
std::vector<SavedPair> own_saved_pairs(const std::string& file, const std::vector<double>& rows,
                                       const std::unordered_map<long long, int>& node,
                                       const FaceIndex<D>& face_of, bool use_owner,
                                       const Kokkos::View<int*, Kokkos::HostSpace>& fowner) {
  constexpr int W = ContactSystem<D>::kPairRow;
  std::vector<SavedPair> pairs;
  long lost = 0;
  for (size_t r = 0; r < rows.size() / W; ++r) {
    const double* v = &rows[r * W];
    bool ok = true;
    for (int k = 0; k <= D; ++k) ok = ok && v[k] >= 0 && v[k] < 2147483648.0 && v[k] == std::floor(v[k]);
    if (!ok)
      throw InputError("checkpoint '" + file + "': contact/pairs row " + std::to_string(r) +
                       " has a node id that is not one (the file is damaged)");
    const auto n = node.find(static_cast<long long>(v[0]));
    if (n == node.end()) continue;  // another process's node
    std::array<long long, D> key;
    for (int k = 0; k < D; ++k) key[k] = static_cast<long long>(v[1 + k]);
    const auto f = face_of.find(key);
    if (f == face_of.end()) {
      ++lost;
      continue;
    }
    pairs.push_back({n->second, use_owner ? fowner(f->second) : 0, f->second, r});
  }
  if (lost > 0)  // (only when a node moved past the contact zone: the run's zone check stops such a run)
    std::fprintf(
        stderr, "fdem: restart: %ld contact histories with faces this process does not hold dropped\n", lost);
  return pairs;
}

// Each node's segment in the order of a search (pair_order: owner element, then face); a pair held
// twice is a damaged file.
void sort_in_search_order(std::vector<SavedPair>& pairs, const std::string& file) {
  std::sort(pairs.begin(), pairs.end(), [](const SavedPair& a, const SavedPair& b) {
    return a.node != b.node ? a.node < b.node : (a.order != b.order ? a.order < b.order : a.face < b.face);
  });
  for (size_t j = 1; j < pairs.size(); ++j)
    if (pairs[j].node == pairs[j - 1].node && pairs[j].face == pairs[j - 1].face)
      throw InputError("checkpoint '" + file + "': contact/pairs holds a pair twice (the file is damaged)");
}

// The pairs with their histories from their rows into P (room for them reserved, P.size set): the
// offsets by node, then the faces, forces, areas, gaps and shear forces.
template <int D>
void upload_saved_pairs(PairList<D>& P, const std::vector<SavedPair>& pairs,
                        const std::vector<double>& rows) {
  constexpr int W = ContactSystem<D>::kPairRow;
  const int n = static_cast<int>(pairs.size());
  const std::pair<int, int> used(0, n);
  auto off = Kokkos::create_mirror_view(P.off);
  auto face = Kokkos::create_mirror_view(Kokkos::subview(P.face, used));
  auto fn = Kokkos::create_mirror_view(Kokkos::subview(P.fn, used));
  auto ac = Kokkos::create_mirror_view(Kokkos::subview(P.ac, used));
  auto g0 = Kokkos::create_mirror_view(Kokkos::subview(P.g0, used));
  auto fs = Kokkos::create_mirror_view(Kokkos::subview(P.fs, used, Kokkos::ALL));
  for (size_t i = 0; i < off.extent(0); ++i) off(i) = 0;
  for (int j = 0; j < n; ++j) {
    const double* v = &rows[pairs[j].row * W + 1 + D];
    ++off(pairs[j].node + 1);
    face(j) = pairs[j].face;
    fn(j) = v[0];
    ac(j) = v[1];
    g0(j) = v[2];
    for (int k = 0; k < D; ++k) fs(j, k) = v[3 + k];
  }
  for (size_t i = 1; i < off.extent(0); ++i) off(i) += off(i - 1);
  Kokkos::deep_copy(P.off, off);
  Kokkos::deep_copy(Kokkos::subview(P.face, used), face);
  Kokkos::deep_copy(Kokkos::subview(P.fn, used), fn);
  Kokkos::deep_copy(Kokkos::subview(P.ac, used), ac);
  Kokkos::deep_copy(Kokkos::subview(P.g0, used), g0);
  Kokkos::deep_copy(Kokkos::subview(P.fs, used, Kokkos::ALL), fs);
}

// The surface nodes' contact areas (narea, by place in the list `nodes` of ns) spread over the nn
// node ids, 0 off the surfaces: the checkpoint's "contact/node_area", one value per node id as
// before the areas were kept by place (the checkpoints of either read by the other).
std::vector<double> areas_by_node(const Kokkos::View<double*>& narea, const Kokkos::View<int*>& nodes, int ns,
                                  int nn) {
  std::vector<double> out(nn, 0.0);
  if (ns == 0) return out;
  const auto a = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), narea);
  const auto n = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), nodes);
  for (int p = 0; p < ns; ++p) out[n(p)] = a(p);
  return out;
}

// A checkpoint's areas by node id (`v`, nn values) into the places of the ns surface nodes.
void areas_from_nodes(const std::vector<double>& v, const Kokkos::View<double*>& narea,
                      const Kokkos::View<int*>& nodes, int ns) {
  if (ns == 0) return;
  auto a = Kokkos::create_mirror_view(narea);
  const auto n = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), nodes);
  for (int p = 0; p < ns; ++p) a(p) = v[n(p)];
  Kokkos::deep_copy(narea, a);
}

}  // namespace

template <int D>
template <class Self, class F>
void ContactSystem<D>::state_fields(Self& self, F&& f) {
  f("contact/xb", self.xb_);
  f("contact/may_meet", self.may_meet_);
  f("contact/need_build", self.need_build_);
  f("contact/since_check", self.since_check_);
  f("contact/builds", self.builds_);
  f("contact/handed_over", self.handed_);
  f("contact/until_recheck", self.until_recheck_);
  f("contact/stale_seen", self.stale_seen_);
}

template <int D>
std::vector<double> ContactSystem<D>::pair_rows(const std::vector<int>& ids) const {
  const int n = cur_.size;
  const std::pair<int, int> used(0, n);
  auto off = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), cur_.off);
  auto face = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), Kokkos::subview(cur_.face, used));
  auto fn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), Kokkos::subview(cur_.fn, used));
  auto ac = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), Kokkos::subview(cur_.ac, used));
  auto g0 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), Kokkos::subview(cur_.g0, used));
  auto fs = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), Kokkos::subview(cur_.fs, used, Kokkos::ALL));
  const std::vector<int> fnode = face_node_table<D>(surf_.fnode);
  auto whole = [&ids](int i) { return static_cast<double>(ids.empty() ? i : ids[static_cast<size_t>(i)]); };
  std::vector<double> rows;
  if (off.extent(0) == 0) return rows;  // (no lists yet)
  for (int i = 0; i < nown_; ++i)
    for (int j = off(i); j < off(i + 1); ++j) {
      bool history = fn(j) != 0.0 || ac(j) != 0.0 || g0(j) != 0.0;
      for (int k = 0; k < D; ++k) history = history || fs(j, k) != 0.0;
      if (!history) continue;  // (a pair the search finds again starts from nothing)
      std::array<double, D> key;
      for (int k = 0; k < D; ++k) key[k] = whole(fnode[static_cast<size_t>(face(j)) * D + k]);
      std::sort(key.begin(), key.end());
      rows.push_back(whole(i));
      rows.insert(rows.end(), key.begin(), key.end());
      rows.push_back(fn(j));
      rows.push_back(ac(j));
      rows.push_back(g0(j));
      for (int k = 0; k < D; ++k) rows.push_back(fs(j, k));
    }
  return rows;
}

template <int D>
void ContactSystem<D>::load_pair_rows(const StateArrays& s, const std::vector<int>& ids) {
  const std::vector<double>& rows = s.array("contact/pairs");
  if (rows.size() % kPairRow != 0)
    throw InputError("checkpoint '" + s.file + "': contact/pairs has " + std::to_string(rows.size()) +
                     " values, not rows of " + std::to_string(kPairRow) + " (the file is damaged)");
  const std::unordered_map<long long, int> node = own_node_index(nown_, ids);
  const FaceIndex<D> face_of = face_index<D>(surf_.fnode, ids);
  Kokkos::View<int*, Kokkos::HostSpace> fowner;
  if (filter_.use) fowner = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), filter_.fowner);
  std::vector<SavedPair> pairs = own_saved_pairs<D>(s.file, rows, node, face_of, filter_.use, fowner);
  sort_in_search_order(pairs, s.file);
  const int n = static_cast<int>(pairs.size());
  reserve_pairs(cur_, std::max(n, 1));
  cur_.size = n;
  upload_saved_pairs<D>(cur_, pairs, rows);
  // the first update builds the lists at the current positions and carries these histories over
  need_build_ = true;
  until_recheck_ = 0;
}

template <int D>
void ContactSystem<D>::save_state(StateArrays& s, const std::vector<int>& ids) const {
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
  s.f64["contact/node_area"] = areas_by_node(surf_.narea, slaves_, ns_, nn_);
  const ContactStatus st = read_status();
  s.put("contact/dissipated", st.dissipated);
  s.put_int("contact/active", static_cast<long long>(st.active));
  s.f64["contact/last_pass"] = {st.d2max, st.v2max, st.stale};
  s.put_int("contact/xb_all", xb_all_ ? 1 : 0);
  s.put_int("contact/list_updates", updates_);
  // for people reading the file (not read back)
  s.put_int("contact/surface_nodes", ns_);
  s.put_int("contact/active_faces", na_);
  s.f64["contact/pairs"] = pair_rows(ids);
  s.put_int("contact/pair_row", kPairRow);
}

template <int D>
void ContactSystem<D>::load_state(const StateArrays& s, const Model<D>& m, const std::vector<int>& ids) {
  refresh_surfaces(m);  // active faces, clusters, surface nodes from m.icontact
  if (!s.has("contact/pair_count")) {  // the whole state of a run over processes: the lists from the rows
    if (s.get_int("contact/pair_row") != kPairRow)
      throw InputError("checkpoint '" + s.file + "': contact/pair_row is not " + std::to_string(kPairRow) +
                       " (a checkpoint of a " + std::to_string(D == 2 ? 3 : 2) + "D run?)");
    may_meet_ = may_meet_ || s.get_int("contact/may_meet") != 0;
    since_check_ = static_cast<int>(s.get_int("contact/since_check"));
    builds_ = static_cast<long>(s.get_int("contact/builds"));
    handed_ = static_cast<long>(s.get_int("contact/handed_over"));
    updates_ = static_cast<long>(s.get_int("contact/list_updates"));
    xb_all_ = true;  // (the first update rebuilds)
    stale_seen_ = 0;
    ContactStatus st;
    st.dissipated = s.get("contact/dissipated");
    auto h = Kokkos::create_mirror_view(status_);
    h() = st;
    Kokkos::deep_copy(status_, h);
    load_pair_rows(s, ids);
    return;
  }
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
  // (the areas refresh_surfaces computed, as the run had them; a checkpoint before they were
  // checkpointed keeps those)
  if (s.has("contact/node_area")) areas_from_nodes(s.array("contact/node_area", nn_), surf_.narea, slaves_, ns_);
  // checkpoints from before the local list updates hold build positions of surface nodes only:
  // their next handover rebuilds
  xb_all_ = s.has("contact/xb_all") && s.get_int("contact/xb_all") != 0;
  updates_ = s.has("contact/list_updates") ? static_cast<long>(s.get_int("contact/list_updates")) : 0;
  auto h = Kokkos::create_mirror_view(status_);
  h() = st;
  Kokkos::deep_copy(status_, h);
}

#define FDEM_CONTACT_STATE(D)                                                             \
  template void ContactSystem<D>::save_state(StateArrays&, const std::vector<int>&) const; \
  template void ContactSystem<D>::load_state(const StateArrays&, const Model<D>&, const std::vector<int>&); \
  template std::vector<double> ContactSystem<D>::pair_rows(const std::vector<int>&) const;              \
  template void ContactSystem<D>::load_pair_rows(const StateArrays&, const std::vector<int>&);
FDEM_CONTACT_STATE(2)
FDEM_CONTACT_STATE(3)
#undef FDEM_CONTACT_STATE

}  // namespace fdem
