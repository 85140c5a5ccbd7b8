#pragma once
// Contact between deformable bodies and fragments (docs/theory.md section 6b): device data and
// kernels, by concern:
//   kernels/contact/geometry.hpp      face normal, projection, stored face geometry, closest point
//   kernels/contact/broad_phase.hpp   box reduction, cell grid, candidate lists, history transfer
//   kernels/contact/surfaces.hpp      active faces, clusters, surface nodes, handover of interfaces
//   kernels/contact/list_update.hpp   candidate lists after a handover by a local search (no rebuild)
//   kernels/contact/contact_pair.hpp  the contact law of one pair (contact_pair), a pass's sums
//   kernels/contact/narrow_phase.hpp  the force kernel over the candidates, spring energy
//   kernels/friction.hpp              the Coulomb shear spring (shared with the platens)
// Host orchestration: src/solver/contact_system.cpp. Launchers copy the Views they need into
// locals before each KOKKOS_LAMBDA (CUDA-safe); no std containers, exceptions or virtual calls in
// kernels; (i, k) indexing only.
#include "kernels/contact/broad_phase.hpp"
#include "kernels/contact/contact_pair.hpp"
#include "kernels/contact/geometry.hpp"
#include "kernels/contact/list_update.hpp"
#include "kernels/contact/narrow_phase.hpp"
#include "kernels/contact/status.hpp"
#include "kernels/contact/surfaces.hpp"
