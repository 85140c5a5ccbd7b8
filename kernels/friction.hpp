#pragma once
// Coulomb friction of an incremental shear spring (docs/theory.md sections 6 and 6b): the one law
// of the node-to-face contacts (contact_pair, kernels/contact/contact_pair.hpp) and of the rigid
// platens (apply_platens, kernels/platens.hpp).
#include "kernels/fdem_kokkos.hpp"

namespace fdem {

// One step of a shear spring: the new shear force and what the step dissipated by slip.
template <int D>
struct ShearStep {
  double Fs[D];  // shear force after the step (global components, in the tangent plane)
  double f2;     // |fs0|^2: the squared old force in this step's tangent plane
  bool slipped;  // the trial force exceeded the limit and was cut back to it
  double slip;   // energy dissipated by the slip (set only when slipped)
};

// The parameters coulomb_shear reads.
struct FrictionLaw {
  double ks, mu, coh;  // Pa/m (times the area), -, Pa
};

// law: anything with ks (Pa/m, times the area), mu and coh (Pa), e.g. FrictionLaw or PlatenDev.
// n: unit normal of the contact (D components); A: contact area; Fn: normal force (>= 0);
// fs: the last step's shear force (global components, scaled to this step's area by the caller)
// and fsn = fs . n; du: relative displacement over the step (node against the other side) and
// dun = du . n. The old force fs0 = fs - fsn n (rotated into this step's tangent plane) plus the
// tangential increment gives the trial force Fs = fs0 - ks A (du - dun n); beyond the Coulomb
// limit lim = mu Fn + coh A it slips back to lim, and the slip dissipates the spring's energy
// before minus after plus the work of du against the mean of the old and new forces (zero while
// sticking, the work the leap-frog sees while slipping).
template <int D, class Law>
KOKKOS_INLINE_FUNCTION ShearStep<D> coulomb_shear(const Law& law, const double* n, double A, double Fn,
                                                  const double (&fs)[D], double fsn, const double (&du)[D],
                                                  double dun) {
  ShearStep<D> r;
  double fs0[D], Fs2 = 0;
  r.f2 = 0;
  for (int k = 0; k < D; ++k) {
    fs0[k] = fs[k] - fsn * n[k];
    r.f2 += fs0[k] * fs0[k];
    r.Fs[k] = fs0[k] - law.ks * A * (du[k] - dun * n[k]);
    Fs2 += r.Fs[k] * r.Fs[k];
  }
  const double lim = law.mu * Fn + law.coh * A;
  const double Fsm = kmath::sqrt(Fs2);
  r.slipped = Fsm > lim;
  r.slip = 0.0;
  if (r.slipped) {
    const double c = Fsm > 0 ? lim / Fsm : 0.0;
    double w = 0;
    for (int k = 0; k < D; ++k) {
      r.Fs[k] *= c;
      w += (fs0[k] + r.Fs[k]) * du[k];
    }
    r.slip = 0.5 * (r.f2 - lim * lim) / (law.ks * A) - 0.5 * w;
  }
  return r;
}

}  // namespace fdem
