#pragma once
// Fragments: connected components of bulk elements. Two elements belong to the same fragment when
// they share a node (elements of a non-fracturable region share their nodes) or when they are
// joined by an interface that has not failed (an interface has failed when all its D integration
// points have damage 1; a partly failed one still holds its two sides together).
//
// The components are found on the nodes, which carries both kinds of link at once: every element
// links its node 0 with its other nodes, every intact interface links its first A-side node with
// its first B-side node. Algorithm (Shiloach-Vishkin style, race-free): labels `lab` and parents
// `par` per node, both starting as the node's own index;
//   hook:     for every link (a, b) whose labels differ, par(max) = min(par(max), min) (atomic min
//             on an int), where max/min are the two labels (roots of a star forest);
//   jump:     lab(i) = par(par(i)) into the other buffer, swap, repeat until no node changes
//             (pointer jumping: O(log depth) passes, each reading one buffer and writing the other);
//   repeat until no link has labels that differ.
// Labels only decrease and always name a node of the same component, so at the end every node
// carries the smallest node index of its component. Each round at least halves the number of
// roots that still have a link to another root, so a mesh of n nodes needs O(log n) rounds.
// The result is deterministic (independent of thread scheduling).
//
// Then fragment ids 0..nf-1 (in order of their smallest node index) by a scan over the roots,
// per-fragment mass (rho V0 per element) and element count by a scatter, and the statistics by
// reductions over the fragments; only a handful of numbers go to the host.
#include <utility>

#include "kernels/cohesive.hpp"
#include "kernels/model.hpp"

namespace fdem {

// Mass distribution: bin b (0 <= b < kFragmentBins - 1) holds fragments whose mass fraction m/M
// lies in [10^-(b+1), 10^-b) (bin 0 includes 1); the last bin holds everything below
// 10^-(kFragmentBins-1).
constexpr int kFragmentBins = 8;

KOKKOS_INLINE_FUNCTION int fragment_bin(double fraction) {
  double edge = 0.1;
  for (int b = 0; b < kFragmentBins - 1; ++b) {
    if (fraction >= edge) return b;
    edge *= 0.1;
  }
  return kFragmentBins - 1;
}

// True when every integration point of interface q has damage 1.
template <int D>
KOKKOS_INLINE_FUNCTION bool interface_failed(const Kokkos::View<double* [D][kPointHistory]>& ihist, int q) {
  for (int k = 0; k < D; ++k) {
    const CohesivePoint h = load_point(ihist, q, k);
    if (cohesive_damage(h) < 1.0) return false;
  }
  return true;
}

// used(i) = 1 for every node of an element (orphan nodes of a mesh file are no fragment).
template <int D>
void mark_used(const Model<D>& m, const Kokkos::View<int*>& used) {
  auto elem = m.elem;
  auto U = used;
  Kokkos::deep_copy(U, 0);
  Kokkos::parallel_for(
      "fdem::fragments::used", Kokkos::RangePolicy<ExecSpace>(0, m.ne), KOKKOS_LAMBDA(const int e) {
        for (int a = 0; a < D + 1; ++a) Kokkos::atomic_fetch_or(&U(elem(e, a)), 1);
      });
}

// Element mass rho V0.
template <int D>
void element_masses(const Model<D>& m, const Kokkos::View<double*>& out) {
  auto vol0 = m.vol0;
  auto emat = m.emat;
  auto mat = m.mat;
  auto M = out;
  Kokkos::parallel_for(
      "fdem::fragments::emass", Kokkos::RangePolicy<ExecSpace>(0, m.ne),
      KOKKOS_LAMBDA(const int e) { M(e) = mat(emat(e), 2) * vol0(e); });
}

// Node labels: on return lab(i) is the smallest node index of i's component. par is work space of
// the same size. Returns the number of hook rounds.
template <int D>
int label_components(const Model<D>& m, const Kokkos::View<int*>& par, const Kokkos::View<int*>& lab) {
  const int nn = m.nn, ne = m.ne, ni = m.ni;
  auto elem = m.elem;
  auto iface = m.iface;
  auto ihist = m.ihist;
  // P: parents being hooked; L: labels (a star forest: every node names its root). They are
  // equal at the start of every round; the pointer jumping swaps the two buffers.
  Kokkos::View<int*> P = par, L = lab;
  {
    auto a = P, b = L;
    Kokkos::parallel_for(
        "fdem::fragments::init", Kokkos::RangePolicy<ExecSpace>(0, nn), KOKKOS_LAMBDA(const int i) {
          a(i) = i;
          b(i) = i;
        });
  }
  int rounds = 0;
  for (;;) {
    ++rounds;
    int changed = 0;
    {
      auto Pw = P;
      auto Lr = L;
      Kokkos::parallel_reduce(
          "fdem::fragments::hook", Kokkos::RangePolicy<ExecSpace>(0, ne + ni),
          KOKKOS_LAMBDA(const int w, int& ch) {
            if (w < ne) {
              const int la = Lr(elem(w, 0));
              for (int k = 1; k <= D; ++k) {
                const int lb = Lr(elem(w, k));
                if (lb != la) {
                  Kokkos::atomic_fetch_min(&Pw(la > lb ? la : lb), la < lb ? la : lb);
                  ++ch;
                }
              }
            } else {
              const int q = w - ne;
              const int la = Lr(iface(q, 0)), lb = Lr(iface(q, D));
              if (la != lb && !interface_failed<D>(ihist, q)) {
                Kokkos::atomic_fetch_min(&Pw(la > lb ? la : lb), la < lb ? la : lb);
                ++ch;
              }
            }
          },
          changed);
    }
    if (changed == 0) break;
    // pointer jumping: L(i) = P(P(i)) from the other buffer, swap, until every node names a root
    // (each pass halves the depth of the trees: O(log depth) passes, no data races)
    for (;;) {
      int deeper = 0;
      auto Pr = P;
      auto Lw = L;
      Kokkos::parallel_reduce(
          "fdem::fragments::jump", Kokkos::RangePolicy<ExecSpace>(0, nn),
          KOKKOS_LAMBDA(const int i, int& d) {
            const int p = Pr(i), g = Pr(p);
            Lw(i) = g;
            if (g != p) ++d;
          },
          deeper);
      std::swap(P, L);
      if (deeper == 0) break;  // P (now L's old buffer) and L hold the same stars
    }
  }
  if (L.data() != lab.data()) Kokkos::deep_copy(lab, L);
  return rounds;
}

// Fragment id of every element (0..nf-1, in order of the fragments' smallest node index).
// used(i) = 1 for nodes of at least one element. root_id: work space per node. Returns nf.
template <int D>
int fragment_ids(const Model<D>& m, const Kokkos::View<int*>& lab, const Kokkos::View<int*>& used,
                 const Kokkos::View<int*>& root_id, const Kokkos::View<int*>& elem_frag) {
  auto L = lab;
  auto U = used;
  auto R = root_id;
  int nf = 0;
  Kokkos::parallel_scan(
      "fdem::fragments::number", Kokkos::RangePolicy<ExecSpace>(0, m.nn),
      KOKKOS_LAMBDA(const int i, int& upd, const bool final) {
        const int is_root = (L(i) == i && U(i) != 0) ? 1 : 0;
        if (final) R(i) = upd;
        upd += is_root;
      },
      nf);
  auto elem = m.elem;
  auto F = elem_frag;
  Kokkos::parallel_for(
      "fdem::fragments::elements", Kokkos::RangePolicy<ExecSpace>(0, m.ne),
      KOKKOS_LAMBDA(const int e) { F(e) = R(L(elem(e, 0))); });
  return nf;
}

// Per fragment: mass (0) and element count (1), summed from the element masses. fstat has nf rows.
inline void fragment_masses(const Kokkos::View<int*>& elem_frag, const Kokkos::View<double*>& emass,
                            const Kokkos::View<double* [2]>& fstat) {
  const int ne = static_cast<int>(elem_frag.extent(0));
  // host backends: one access() per chunk of elements into per-thread copies; GPUs: atomics
  constexpr int chunk =
      Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible ? kScatterChunk : 1;
  const int nw = (ne + chunk - 1) / chunk;
  auto F = elem_frag;
  auto M = emass;
  Kokkos::deep_copy(fstat, 0.0);
  Kokkos::Experimental::ScatterView<double* [2]> sc(fstat);
  Kokkos::parallel_for(
      "fdem::fragments::mass", Kokkos::RangePolicy<ExecSpace>(0, nw), KOKKOS_LAMBDA(const int c) {
        auto acc = sc.access();
        const int e0 = c * chunk, e1 = kmin(e0 + chunk, ne);
        for (int e = e0; e < e1; ++e) {
          acc(F(e), 0) += M(e);
          acc(F(e), 1) += 1.0;
        }
      });
  auto S = fstat;
  Kokkos::Experimental::contribute(S, sc);
}

// Reductions over the fragments: total mass (0), single-element fragments (1), then per bin the
// number of fragments (2 + b) and their mass (2 + kFragmentBins + b). largest: the largest mass.
using FragmentSums = SumN<2 + 2 * kFragmentBins>;

inline FragmentSums fragment_statistics(const Kokkos::View<double* [2]>& fstat, int nf, double& largest) {
  auto S = fstat;
  double total = 0, big = 0;
  Kokkos::parallel_reduce(
      "fdem::fragments::total", Kokkos::RangePolicy<ExecSpace>(0, nf),
      KOKKOS_LAMBDA(const int f, double& s) { s += S(f, 0); }, total);
  Kokkos::parallel_reduce(
      "fdem::fragments::largest", Kokkos::RangePolicy<ExecSpace>(0, nf),
      KOKKOS_LAMBDA(const int f, double& s) {
        if (S(f, 0) > s) s = S(f, 0);
      },
      Kokkos::Max<double>(big));
  FragmentSums out;
  const double inv = total > 0 ? 1.0 / total : 0.0;
  Kokkos::parallel_reduce(
      "fdem::fragments::distribution", Kokkos::RangePolicy<ExecSpace>(0, nf),
      KOKKOS_LAMBDA(const int f, FragmentSums& s) {
        const double mf = S(f, 0);
        s.v[0] += mf;
        s.v[1] += S(f, 1) == 1.0 ? 1.0 : 0.0;
        const int b = fragment_bin(mf * inv);
        s.v[2 + b] += 1.0;
        s.v[2 + kFragmentBins + b] += mf;
      },
      out);
  largest = big;
  return out;
}

}  // namespace fdem
