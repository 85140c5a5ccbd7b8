#pragma once
// The contact system's running totals on the device: the narrow phase's sums of each pass
// (ContactSums, kernels/contact/contact_pair.hpp) added up in step order without a host
// reduction, so that an unsampled step does not wait for the device (ContactSystem::update).
#include "kernels/contact/contact_pair.hpp"

namespace fdem {

// The contact system's running totals on the device (ContactSystem::update): what the host reads
// on the steps it re-checks its candidate lists, and for the energies and statistics.
struct ContactStatus {
  double dissipated = 0;  // energy dissipated by friction and released shear springs so far
  double active = 0;      // contacts in the last pass
  double d2max = 0;       // largest squared displacement of a surface node since the last build (last pass)
  double v2max = 0;       // largest squared speed of a surface node (last pass)
  double stale = 0;       // passes with a node beyond half the skin from its build position
};

// Adds the sums of the last pass to the status (one work item: the totals are summed in step order,
// as on the host before). half_skin: half the Verlet skin.
inline void contact_account(const Kokkos::View<ContactSums>& pass, const Kokkos::View<ContactStatus>& status,
                            double half_skin) {
  auto p = pass;
  auto st = status;
  const double h2 = half_skin * half_skin;
  Kokkos::parallel_for(
      "fdem::contact::account", Kokkos::RangePolicy<ExecSpace>(0, 1), KOKKOS_LAMBDA(const int) {
        const ContactSums r = p();
        ContactStatus& s = st();
        s.dissipated += r.dissipated;
        s.active = r.active;
        s.d2max = r.d2max;
        s.v2max = r.v2max;
        if (r.d2max > h2) s.stale += 1.0;
      });
}

}  // namespace fdem
