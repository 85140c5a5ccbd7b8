#pragma once
// The kernels of one explicit step, and the reductions done on output/check steps only, by
// concern: interface kinematics (interface.hpp), the fused force pass (forces.hpp), rigid platens
// (platens.hpp), the node update (nodes.hpp), output reductions (outputs.hpp) and state checks
// (checks.hpp). Free functions ("launchers") and functors that copy the Views they need, so that
// the same source compiles for OpenMP and CUDA (no virtual calls, no std containers, no
// exceptions).
#include "kernels/checks.hpp"
#include "kernels/forces.hpp"
#include "kernels/interface.hpp"
#include "kernels/nodes.hpp"
#include "kernels/outputs.hpp"
#include "kernels/platens.hpp"
