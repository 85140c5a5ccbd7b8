#pragma once
// The internal forces of one explicit step (docs/theory.md sections 2 to 4): bulk elements
// (kernels/elastic.hpp) and cohesive interfaces (kernels/interface.hpp) in one fused pass that
// scatters into the nodal forces.
#include "kernels/cohesive.hpp"
#include "kernels/elastic.hpp"
#include "kernels/interface.hpp"
#include "kernels/model.hpp"

namespace fdem {

// Chunk of items per work item for the scatter: 256 on host backends (one access() per chunk),
// 1 on GPUs (one thread per item, atomics).
constexpr int kChunk =
    Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible ? kScatterChunk : 1;

// Work item c of the force pass. fused (host backends): element chunk c and the interfaces whose
// side A lies in it (Model::ichunk: one pass over the nodes, side A's positions and forces are
// still in cache); else bulk chunks (c < nbc), then interface chunks. PerIface: the interfaces
// take their own parameters (InterfaceData::params); else all take InterfaceData::coh. Fric: the
// model has slip states (InterfaceData::islip): a point that has begun to soften reads and writes
// its slip state too (the others never touch it).
template <int D, bool PerIface, bool Fric>
struct ForceKernel {
  Kokkos::View<double* [D]> x;
  Kokkos::View<double* [D]> v;  // v(n - 1/2): the step's motion of a softening point's node pair (Fric)
  ElementData<D> el;
  InterfaceData<D> in;
  ForceScatter<D> sf;
  int nbc;
  bool fused;

  // Bulk element e.
  template <class Acc>
  KOKKOS_INLINE_FUNCTION void bulk(const int e, Acc& acc) const {
    double xe[D + 1][D], G[D][D], fe[D + 1][D];
    gather_element<D>(x, el, e, xe, G);
    const int mt = el.emat(e);
    element_forces<D>(xe, G, el.vol0(e), el.mat(mt, 0), el.mat(mt, 1), fe);
    for (int a = 0; a < D + 1; ++a)
      for (int i = 0; i < D; ++i) acc(el.elem(e, a), i) += fe[a][i];
  }

  // Interface q: its history and, while it carries, its forces.
  template <class Acc>
  KOKKOS_INLINE_FUNCTION void interface(const int q, Acc& acc) const {
    // Model::icontact: nonzero once the interface carries nothing (handed over to contact: its
    // faces are in contact instead; or, without contact, come apart for good: interface_apart).
    if (in.icontact(q)) return;
    const bool handover = in.contact_handover;
    double xa[D][D], xb[D][D], fa[D][D], fb[D][D];
    CohesivePoint h[D];
    SlipPoint<D> sl[D];
    gather_interface<D>(x, in.iface, q, xa, xb);
    for (int k = 0; k < D; ++k) h[k] = load_point(in.ihist, q, k);
    const CohesiveParams p = PerIface ? in.params(q) : in.coh;
    // the slip state and the step's motion of a softening point with a residual friction only
    // (a point that has not begun to soften, or under the paper's law, reads neither)
    const bool slips = Fric && p.tanphir >= 0.0;
    for (int k = 0; k < D; ++k) sl[k] = slips && h[k].dm0 > 0.0 ? load_slip<D>(in.islip, q, k) : zero_slip<D>();
    if (interface_apart<D>(xa, xb, h)) {
      interface_fail_all<D, Fric>(xa, xb, p, h, sl);
      for (int k = 0; k < D; ++k) {
        store_point(in.ihist, q, k, h[k]);
        if (slips) store_slip<D>(in.islip, q, k, sl[k]);
      }
      if (handover) Kokkos::atomic_exchange(&in.icontact_pending(), 1);
      else in.icontact(q) = 1;
      return;
    }
    CohesivePoint h0[D];
    for (int k = 0; k < D; ++k) h0[k] = h[k];
    double du[D][D];  // x(n) - x(n-1) of each node pair: v(n - 1/2) dt (softening points, Fric)
    for (int k = 0; k < D; ++k)
      for (int i = 0; i < D; ++i)
        du[k][i] = slips && h[k].dm0 > 0.0 ? (v(in.iface(q, D + k), i) - v(in.iface(q, k), i)) * in.step_dt : 0.0;
    const double dmean = interface_forces<D, Fric>(xa, xb, in.iarea(q), p, h, sl, fa, fb, du);
    if (handover && dmean >= 1.0 && interface_parted<D>(xa, xb, in.handover_slip))
      Kokkos::atomic_exchange(&in.icontact_pending(), 1);
    for (int k = 0; k < D; ++k) {
      // the history is written only when the step changed it (most points of a run stay
      // undamaged or unload: no write traffic for them); the slip state of a softening point
      // (its slip follows the faces' every move)
      if (!same_point(h[k], h0[k])) store_point(in.ihist, q, k, h[k]);
      if (slips && h[k].dm0 > 0.0) store_slip<D>(in.islip, q, k, sl[k]);
      for (int i = 0; i < D; ++i) {
        acc(in.iface(q, k), i) += fa[k][i];
        acc(in.iface(q, D + k), i) += fb[k][i];
      }
    }
  }

  KOKKOS_INLINE_FUNCTION void operator()(const int c) const {
    auto acc = sf.access();
    if (fused) {
      const int e1 = kmin((c + 1) * kChunk, el.bulk_elems());
      for (int e = c * kChunk; e < e1; ++e) bulk(e, acc);
      for (int q = in.ichunk(c); q < in.ichunk(c + 1); ++q) interface(q, acc);
    } else if (c < nbc) {
      const int e1 = kmin((c + 1) * kChunk, el.bulk_elems());
      for (int e = c * kChunk; e < e1; ++e) bulk(e, acc);
    } else {
      const int i0 = (c - nbc) * kChunk, i1 = kmin(i0 + kChunk, in.ni);
      for (int q = i0; q < i1; ++q) interface(q, acc);
    }
  }
};

// Internal forces of bulk elements and interfaces, fused in one kernel and scattered into m.f
// (which the node update left at zero). contribute = false: the sums stay in sf (the caller adds
// the contact forces to it and contributes).
// Work items: on host backends each chunk of kChunk elements with the interfaces whose side A
// lies in it (Model::ichunk: one pass over the nodes), else bulk chunks, then interface chunks.
template <int D>
void compute_forces(const Model<D>& m, ForceScatter<D>& sf, bool contribute = true) {
  const int ne = m.ne, ni = m.ni;
  const int nbc = (ne + kChunk - 1) / kChunk, nic = (ni + kChunk - 1) / kChunk;
  const bool fused = kChunk > 1 && static_cast<int>(m.ichunk.extent(0)) == nbc + 1;
  sf.reset();
  const Kokkos::RangePolicy<ExecSpace> policy(0, fused ? nbc : nbc + nic);
  auto run = [&](auto kernel) { Kokkos::parallel_for("fdem::forces", policy, kernel); };
  if (m.per_interface()) {
    if (m.has_slip()) run(ForceKernel<D, true, true>{m.x, m.v, m.elements(), m.interfaces(), sf, nbc, fused});
    else run(ForceKernel<D, true, false>{m.x, m.v, m.elements(), m.interfaces(), sf, nbc, fused});
  } else {
    if (m.has_slip()) run(ForceKernel<D, false, true>{m.x, m.v, m.elements(), m.interfaces(), sf, nbc, fused});
    else run(ForceKernel<D, false, false>{m.x, m.v, m.elements(), m.interfaces(), sf, nbc, fused});
  }
  if (!contribute) return;  // the caller adds more (contact) and contributes
  auto f = m.f;
  Kokkos::Experimental::contribute(f, sf);
}

}  // namespace fdem
