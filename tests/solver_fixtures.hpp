#pragma once
// Small meshes and cases built in code for the solver tests.
#include <cmath>
#include <string>
#include <vector>

#include "io/case.hpp"
#include "mesh/mesh.hpp"

namespace fdem_test {

inline fdem::Case basic_case(int dim, double E = 33e9, double nu = 0.25, double rho = 2700) {
  fdem::Case c;
  c.file = "test-case";
  c.name = "test";
  c.dim = dim;
  c.materials = {fdem::BulkMaterial{"rock", rho, E, nu}};
  c.region_material = {{"body", 0}};
  c.safety_factor = 0.5;
  c.end_time = 1.0;
  c.plane_stress = false;
  c.thickness = 1.0;
  return c;
}

inline fdem::InterfaceMaterial strong_interface(double kn, double ks) {
  fdem::InterfaceMaterial m;
  m.name = "if";
  m.kn = kn;
  m.ks = ks;
  m.ft = 1e30;
  m.c = 1e30;
  m.phi = 0.5;
  m.Gnc = 1e30;
  m.Gsc = 1e30;
  m.eta = 2;
  return m;
}

// A 2D bar of nb square blocks (side d, height h), each block 2 triangles with its own 4 nodes,
// and a 4-node interface between neighbouring blocks (A = left block, B = right block).
// Node sets: "left" (left end), "right" (right end), "corner" (bottom-left node).
inline fdem::HostMesh block_bar(int nb, double d, double h) {
  fdem::HostMesh m;
  m.dim = 2;
  m.region_names = {"body"};
  for (int j = 0; j < nb; ++j) {
    const double x0 = j * d;
    const int b = 4 * j;  // bl, br, tr, tl
    for (double p : {x0, 0.0, x0 + d, 0.0, x0 + d, h, x0, h}) m.X.push_back(p);
    for (int n : {b, b + 1, b + 2, b, b + 2, b + 3}) m.elems.push_back(n);
    m.elem_region.push_back(0);
    m.elem_region.push_back(0);
    if (j > 0) {
      const int a = 4 * (j - 1);
      // A side: br, tr of the left block (normal +x); B side: bl, tl of this block
      for (int n : {a + 1, a + 2, b, b + 3}) m.ifaces.push_back(n);
      m.iface_elems.push_back(2 * (j - 1));  // (a, a+1, a+2) holds br, tr
      m.iface_elems.push_back(2 * j + 1);    // (b, b+2, b+3) holds bl, tl
    }
  }
  m.node_sets["left"] = {0, 3};
  m.node_sets["corner"] = {0};
  m.node_sets["right"] = {4 * (nb - 1) + 1, 4 * (nb - 1) + 2};
  for (int i = 0; i < m.num_nodes(); ++i) m.node_origin.push_back(i);
  return m;
}

// Deterministic pseudo-random number in [-1, 1].
inline double prand(unsigned& s) {
  s = s * 1664525u + 1013904223u;
  return (s >> 8) * (2.0 / 16777216.0) - 1.0;
}

}  // namespace fdem_test
