#include "solver/fragment_parts.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/union_find.hpp"

namespace fdem {

std::vector<int> join_tokens(const std::vector<double>& all, int processes, int width,
                             std::vector<double>& values, std::vector<int>& offset) {
  offset.assign(static_cast<size_t>(processes) + 1, 0);
  values.clear();
  std::vector<std::array<long, 3>> edges;  // (process, its token, process, its token)
  std::vector<int> from;
  size_t j = 0;
  for (int p = 0; p < processes; ++p) {
    if (j + 2 > all.size()) throw std::logic_error("join_tokens: a process's buffer is cut short");
    const int tokens = static_cast<int>(all[j]);
    const size_t nedges = static_cast<size_t>(all[j + 1]);
    j += 2;
    const size_t nv = static_cast<size_t>(tokens) * width;
    if (j + nv + 3 * nedges > all.size())
      throw std::logic_error("join_tokens: a process's buffer is cut short");
    offset[p + 1] = offset[p] + tokens;
    values.insert(values.end(), all.begin() + static_cast<long>(j), all.begin() + static_cast<long>(j + nv));
    j += nv;
    for (size_t k = 0; k < nedges; ++k, j += 3) {
      edges.push_back(
          {static_cast<long>(all[j]), static_cast<long>(all[j + 1]), static_cast<long>(all[j + 2])});
      from.push_back(p);
    }
  }
  UnionFind uf(offset[processes]);
  for (size_t k = 0; k < edges.size(); ++k) {
    const long q = edges[k][1];
    if (q < 0 || q >= processes || edges[k][2] < 0 || edges[k][2] >= offset[q + 1] - offset[q])
      throw std::logic_error("join_tokens: an edge names a token that does not exist");
    uf.join(offset[from[k]] + static_cast<int>(edges[k][0]), offset[q] + static_cast<int>(edges[k][2]));
  }
  std::vector<int> rep(static_cast<size_t>(offset[processes]));
  for (size_t t = 0; t < rep.size(); ++t) rep[t] = uf.find(static_cast<int>(t));
  return rep;
}

std::vector<int> number_classes(const std::vector<int>& rep, const std::vector<double>& values, int width,
                                int key_col, int count_col, int& n) {
  const size_t tokens = rep.size(), w = static_cast<size_t>(width);
  std::vector<double> key(tokens, std::numeric_limits<double>::infinity()), count(tokens, 0.0);
  for (size_t t = 0; t < tokens; ++t) {
    const size_t r = static_cast<size_t>(rep[t]);
    key[r] = std::min(key[r], values[t * w + key_col]);
    count[r] += values[t * w + count_col];
  }
  std::vector<int> reps;
  for (size_t t = 0; t < tokens; ++t)
    if (rep[t] == static_cast<int>(t) && count[t] > 0) reps.push_back(static_cast<int>(t));
  std::sort(reps.begin(), reps.end(), [&key](int a, int b) { return key[a] < key[b]; });
  std::vector<int> number(tokens, -1), out(tokens, -1);
  for (size_t i = 0; i < reps.size(); ++i) number[reps[i]] = static_cast<int>(i);
  for (size_t t = 0; t < tokens; ++t) out[t] = number[rep[t]];
  n = static_cast<int>(reps.size());
  return out;
}

void FragmentPieces::add(int f, double m, const double* mc, const double* l, const double* h) {
  frag.push_back(f);
  mass.push_back(m);
  moment.insert(moment.end(), mc, mc + 3);
  lo.insert(lo.end(), l, l + 3);
  hi.insert(hi.end(), h, h + 3);
}

nlohmann::json largest_fragments(const FragmentPieces& p, const std::vector<double>& masses, int dim) {
  std::vector<int> order(masses.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&masses](int a, int b) { return masses[a] > masses[b]; });
  if (order.size() > 10) order.resize(10);
  std::vector<int> rank(masses.size(), -1);
  for (size_t r = 0; r < order.size(); ++r) rank[order[r]] = static_cast<int>(r);
  const size_t n = order.size(), d = static_cast<size_t>(dim);
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::vector<double> m(n, 0.0), c(3 * n, 0.0), lo(3 * n, inf), hi(3 * n, -inf);
  double total = 0;
  for (size_t i = 0; i < p.frag.size(); ++i) {
    total += p.mass[i];
    const int r = p.frag[i] >= 0 ? rank[p.frag[i]] : -1;
    if (r < 0) continue;
    m[r] += p.mass[i];
    for (size_t k = 0; k < 3; ++k) {
      c[3 * r + k] += p.moment[3 * i + k];
      lo[3 * r + k] = std::min(lo[3 * r + k], p.lo[3 * i + k]);
      hi[3 * r + k] = std::max(hi[3 * r + k], p.hi[3 * i + k]);
    }
  }
  nlohmann::json out = nlohmann::json::array();
  for (size_t r = 0; r < n; ++r) {
    std::vector<double> cr(d), lr(d), hr(d);
    for (size_t k = 0; k < d; ++k) {
      cr[k] = m[r] > 0 ? c[3 * r + k] / m[r] : 0.0;
      lr[k] = lo[3 * r + k];
      hr[k] = hi[3 * r + k];
    }
    out.push_back({{"fraction", total > 0 ? m[r] / total : 0.0},
                   {"reference_centroid", cr},
                   {"reference_box_min", lr},
                   {"reference_box_max", hr}});
  }
  return out;
}

namespace {

// The edges between this process's tokens and its neighbours': each own node in a send list
// sends its token (as the step's exchange sends positions: Parts' lists), each exchanged ghost
// receives its owner's; per ghost the edge (its token here, the owner, the owner's token), each
// edge once. token(n): the token of local node n.
template <int D, class Token>
std::vector<double> ghost_edges(const Parts<D>& parts, Token&& token) {
  const std::vector<int>& nb = parts.neighbours();
  const std::vector<std::vector<int>>&send = parts.send_lists(), &recv = parts.recv_lists();
  std::vector<int> so(1, 0), ro(1, 0);
  for (size_t k = 0; k < nb.size(); ++k) {
    so.push_back(so.back() + static_cast<int>(send[k].size()));
    ro.push_back(ro.back() + static_cast<int>(recv[k].size()));
  }
  Kokkos::View<double*> sb("fdem::fragments::send", so.back()), rb("fdem::fragments::recv", ro.back());
  auto sh = Kokkos::create_mirror_view(sb);
  for (size_t k = 0; k < nb.size(); ++k)
    for (size_t i = 0; i < send[k].size(); ++i) sh(so[k] + i) = token(send[k][i]);
  Kokkos::deep_copy(sb, sh);
  parts.comm().exchange(nb, sb, so, rb, ro, 1);
  auto rh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), rb);
  std::vector<std::array<long, 3>> e;
  for (size_t k = 0; k < nb.size(); ++k)
    for (size_t i = 0; i < recv[k].size(); ++i)
      e.push_back({token(recv[k][i]), nb[k], static_cast<long>(rh(ro[k] + i))});
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  std::vector<double> out;
  out.reserve(3 * e.size());
  for (const auto& x : e) out.insert(out.end(), {double(x[0]), double(x[1]), double(x[2])});
  return out;
}

// Tokens: a process's components (named by a representative node) numbered in order of first use.
struct Tokens {
  std::vector<int> of;  // representative node -> token (-1: none yet)
  int count = 0;
  explicit Tokens(int nodes) : of(static_cast<size_t>(nodes), -1) {}
  int operator()(int rep) {
    int& t = of[static_cast<size_t>(rep)];
    if (t < 0) t = count++;
    return t;
  }
};

// A buffer for join_tokens: [tokens, edges, values, edges].
std::vector<double> buffer(int tokens, const std::vector<double>& values, const std::vector<double>& edges) {
  std::vector<double> b = {static_cast<double>(tokens), static_cast<double>(edges.size() / 3)};
  b.insert(b.end(), values.begin(), values.end());
  b.insert(b.end(), edges.begin(), edges.end());
  return b;
}

}  // namespace

template <int D>
PartFragments<D>::PartFragments(const Simulation<D>& sim)
    : comm_(sim.parts().comm()),
      root_(sim.parts().root()),
      own_elems_(sim.m.owned_elems()),
      par_("fdem::fragments::par", sim.m.nn),
      lab_("fdem::fragments::lab", sim.m.nn) {
  const Model<D>& m = sim.m;
  auto vol = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.vol0);
  auto mat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.mat);
  auto emat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.emat);
  emass_.resize(static_cast<size_t>(own_elems_));
  for (int e = 0; e < own_elems_; ++e) emass_[e] = mat(emat(e), 2) * vol(e);
  label_bodies(sim);
}

// The initial bodies: every element joins its nodes and every interface its sides (failed or
// not), on the host; tokens by their own elements' smallest whole-mesh element index.
template <int D>
void PartFragments<D>::label_bodies(const Simulation<D>& sim) {
  const Model<D>& m = sim.m;
  auto el = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.elem);
  auto fc = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.iface);
  UnionFind uf(m.nn);
  for (int e = 0; e < m.ne; ++e)
    for (int a = 1; a <= D; ++a) uf.join(el(e, 0), el(e, a));
  for (int q = 0; q < m.ni; ++q) uf.join(fc(q, 0), fc(q, D));
  Tokens tok(m.nn);
  elem_body_tok_.resize(static_cast<size_t>(own_elems_));
  node0_.resize(static_cast<size_t>(own_elems_));
  for (int e = 0; e < own_elems_; ++e) {
    node0_[e] = el(e, 0);
    elem_body_tok_[e] = tok(uf.find(node0_[e]));
  }
  const std::vector<double> edges = ghost_edges<D>(sim.parts(), [&](int n) { return tok(uf.find(n)); });
  // per token: the smallest whole-mesh index of its own elements, and their count
  std::vector<double> values(2 * static_cast<size_t>(tok.count), 0.0);
  for (int t = 0; t < tok.count; ++t) values[2 * t] = std::numeric_limits<double>::infinity();
  const std::vector<int>& eg = sim.parts().elem_global();
  for (int e = 0; e < own_elems_; ++e) {
    const int t = elem_body_tok_[e];
    values[2 * t] = std::min(values[2 * t], double(eg[e]));
    values[2 * t + 1] += 1;
  }
  std::vector<double> all;
  comm_.gather(buffer(tok.count, values, edges), all);
  if (!root_) return;
  std::vector<double> vals;
  const std::vector<int> rep = join_tokens(all, comm_.size(), 2, vals, body_offset_);
  body_of_tok_ = number_classes(rep, vals, 2, 0, 1, bodies_);
}

// This process's tokens of the present state, for join_tokens: per token the smallest whole-mesh
// node index, the own elements' mass and count; the edges to the neighbours' tokens (ghost_edges).
template <int D>
std::vector<double> PartFragments<D>::token_buffer(const Simulation<D>& sim) {
  const Model<D>& m = sim.m;
  last_.rounds = label_components<D>(m, par_, lab_);
  auto lab = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), lab_);
  const std::vector<int>& ng = sim.parts().node_global();
  Tokens tok(m.nn);
  elem_tok_.resize(static_cast<size_t>(own_elems_));
  for (int e = 0; e < own_elems_; ++e) elem_tok_[e] = tok(lab(node0_[e]));
  const std::vector<double> edges = ghost_edges<D>(sim.parts(), [&](int n) { return tok(lab(n)); });
  tokens_ = tok.count;
  std::vector<double> values(3 * static_cast<size_t>(tokens_), 0.0);
  for (int t = 0; t < tokens_; ++t) values[3 * t] = std::numeric_limits<double>::infinity();
  for (int e = 0; e < own_elems_; ++e) {
    values[3 * elem_tok_[e] + 1] += emass_[e];
    values[3 * elem_tok_[e] + 2] += 1;
  }
  for (int n = 0; n < m.nn; ++n) {  // (a node of no element has no token)
    const int t = tok.of[lab(n)];
    if (t >= 0) values[3 * t] = std::min(values[3 * t], double(ng[n]));
  }
  return buffer(tokens_, values, edges);
}

// Process 0: the fragments from every process's tokens, and their statistics (as
// fragment_statistics in kernels/fragments.hpp).
template <int D>
void PartFragments<D>::take_classes(const std::vector<double>& all) {
  std::vector<double> vals;
  const std::vector<int> rep = join_tokens(all, comm_.size(), 3, vals, tok_offset_);
  FragmentStats& s = last_;
  tok_frag_ = number_classes(rep, vals, 3, 0, 2, s.count);
  tok_vals_ = vals;
  frag_mass_.assign(static_cast<size_t>(s.count), 0.0);
  std::vector<double> count(static_cast<size_t>(s.count), 0.0);
  for (size_t t = 0; t < tok_frag_.size(); ++t) {
    if (tok_frag_[t] < 0) continue;
    frag_mass_[tok_frag_[t]] += vals[3 * t + 1];
    count[tok_frag_[t]] += vals[3 * t + 2];
  }
  s.total_mass = s.largest_mass = 0;
  for (double x : frag_mass_) {
    s.total_mass += x;
    s.largest_mass = std::max(s.largest_mass, x);
  }
  const double inv = s.total_mass > 0 ? 1.0 / s.total_mass : 0.0;
  s.single_element = 0;
  s.bin_count.fill(0);
  s.bin_mass_fraction.fill(0);
  for (size_t f = 0; f < frag_mass_.size(); ++f) {
    s.single_element += count[f] == 1.0;
    const int b = fragment_bin(frag_mass_[f] * inv);
    s.bin_count[b] += 1;
    s.bin_mass_fraction[b] += frag_mass_[f] * inv;
  }
  s.largest_fraction = s.largest_mass * inv;
}

template <int D>
const FragmentStats& PartFragments<D>::compute(const Simulation<D>& sim) {
  std::vector<double> all;
  const std::vector<double> mine = token_buffer(sim);
  comm_.gather(mine, all);
  gathered_bytes_ = sizeof(double) * static_cast<double>(root_ ? all.size() : mine.size());
  if (root_) take_classes(all);
  return last_;
}

template <int D>
void PartFragments<D>::element_ids(std::vector<int>& ids) const {
  std::vector<std::vector<char>> parts;
  if (root_)
    for (int p = 0; p < comm_.size(); ++p) {
      const int* first = tok_frag_.data() + tok_offset_[p];
      const size_t n = static_cast<size_t>(tok_offset_[p + 1] - tok_offset_[p]);
      parts.emplace_back(reinterpret_cast<const char*>(first), reinterpret_cast<const char*>(first + n));
    }
  std::vector<char> mine;
  comm_.scatter_bytes(parts, mine);
  if (mine.size() != sizeof(int) * static_cast<size_t>(tokens_))
    throw std::logic_error("PartFragments: " + std::to_string(mine.size()) + " bytes of fragment ids for " +
                           std::to_string(tokens_) + " tokens");
  std::vector<int> frag(static_cast<size_t>(tokens_));
  if (tokens_ > 0) std::memcpy(frag.data(), mine.data(), mine.size());
  ids.resize(static_cast<size_t>(own_elems_));
  for (int e = 0; e < own_elems_; ++e) ids[e] = frag[elem_tok_[e]];
}

// Per token: its body token, then its own elements' mass-weighted reference centroid sums and the
// box of their reference centroids; process 0 makes the pieces of the fragments from every
// process's tokens.
template <int D>
typename PartFragments<D>::Ends PartFragments<D>::ends(const Simulation<D>& sim) const {
  const Model<D>& m = sim.m;
  auto el = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.elem);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), m.X);
  constexpr size_t w = 10;  // body token, moment (3), lo (3), hi (3)
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::vector<double> v(w * static_cast<size_t>(tokens_), 0.0);
  for (int t = 0; t < tokens_; ++t) {
    v[w * t] = -1;
    for (int k = 0; k < 3; ++k) v[w * t + 4 + k] = v[w * t + 7 + k] = k < D ? inf : 0.0;
    for (int k = 0; k < D; ++k) v[w * t + 7 + k] = -inf;
  }
  for (int e = 0; e < own_elems_; ++e) {
    double* row = &v[w * elem_tok_[e]];
    row[0] = elem_body_tok_[e];
    for (int k = 0; k < D; ++k) {
      double c = 0;
      for (int a = 0; a <= D; ++a) c += X(el(e, a), k) / (D + 1);
      row[1 + k] += emass_[e] * c;
      row[4 + k] = std::min(row[4 + k], c);
      row[7 + k] = std::max(row[7 + k], c);
    }
  }
  std::vector<double> all;
  comm_.gather(buffer(tokens_, v, {}), all);
  Ends out;
  if (!root_) return out;
  std::vector<double> vals;
  std::vector<int> offset;
  join_tokens(all, comm_.size(), static_cast<int>(w), vals, offset);
  if (offset != tok_offset_)
    throw std::logic_error("PartFragments::ends: the tokens are not the last compute's");
  FragmentPieces pieces;
  std::vector<int> body, elements;
  for (int p = 0; p < comm_.size(); ++p)
    for (int t = tok_offset_[p]; t < tok_offset_[p + 1]; ++t) {
      const double* row = &vals[w * t];
      if (tok_frag_[t] < 0 || !(tok_vals_[3 * t + 2] > 0)) continue;  // no own element
      pieces.add(tok_frag_[t], tok_vals_[3 * t + 1], row + 1, row + 4, row + 7);
      body.push_back(body_of_tok_[body_offset_[p] + static_cast<int>(row[0])]);
      elements.push_back(static_cast<int>(tok_vals_[3 * t + 2]));
    }
  out.largest = largest_fragments(pieces, frag_mass_, D);
  if (bodies_ < 2) return out;
  std::vector<double> centroid(pieces.moment.size());  // body_fragments weighs centroids by mass
  for (size_t i = 0; i < centroid.size(); ++i) centroid[i] = pieces.moment[i] / pieces.mass[i / 3];
  out.bodies = body_fragments(body, bodies_, pieces.frag, frag_mass_, pieces.mass, centroid);
  for (BodyFragments& b : out.bodies) b.elements = 0;  // (it counted the pieces)
  for (size_t i = 0; i < body.size(); ++i) out.bodies[body[i]].elements += elements[i];
  return out;
}

template class PartFragments<2>;
template class PartFragments<3>;

}  // namespace fdem
