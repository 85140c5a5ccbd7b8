// Mesh module: element checks, quality, boundary faces, build_mesh dispatch (locality reordering:
// locality.cpp).
#include "mesh/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <sstream>
#include <unordered_set>

#include "common/error.hpp"
#include "mesh/grains.hpp"
#include "mesh/memory_budget.hpp"
#include "mesh/mesh_internal.hpp"
#include "mesh/particles.hpp"
#include "mesh/refine.hpp"

namespace fdem {

int HostMesh::region_index(const std::string& name) const {
  for (std::size_t i = 0; i < region_names.size(); ++i)
    if (region_names[i] == name) return static_cast<int>(i);
  return -1;
}

namespace mesh_detail {

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

double signed_measure(const HostMesh& m, int e) {
  const int* n = &m.elems[static_cast<std::size_t>(e) * (m.dim + 1)];
  const double* X = m.X.data();
  if (m.dim == 2) {
    const double* a = X + 2 * n[0];
    const double* b = X + 2 * n[1];
    const double* c = X + 2 * n[2];
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
  }
  const double* a = X + 3 * n[0];
  double u[3], v[3], w[3];
  for (int k = 0; k < 3; ++k) {
    u[k] = X[3 * n[1] + k] - a[k];
    v[k] = X[3 * n[2] + k] - a[k];
    w[k] = X[3 * n[3] + k] - a[k];
  }
  return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
          u[2] * (v[0] * w[1] - v[1] * w[0])) /
         6.0;
}

std::array<double, 3> centroid(const HostMesh& m, int e) {
  std::array<double, 3> c{0, 0, 0};
  const int npe = m.dim + 1;
  for (int a = 0; a < npe; ++a) {
    const int n = m.elems[static_cast<std::size_t>(e) * npe + a];
    for (int k = 0; k < m.dim; ++k) c[k] += m.X[static_cast<std::size_t>(n) * m.dim + k];
  }
  for (int k = 0; k < m.dim; ++k) c[k] /= npe;
  return c;
}

void orient_positively(HostMesh& m) {
  const int npe = m.dim + 1;
  for (int e = 0; e < m.num_elems(); ++e)
    if (signed_measure(m, e) < 0)
      std::swap(m.elems[static_cast<std::size_t>(e) * npe + 1],
                m.elems[static_cast<std::size_t>(e) * npe + 2]);
}

void check_elements_impl(const HostMesh& mesh, const std::string& source,
                         const std::vector<std::size_t>* elem_tags) {
  const int dim = mesh.dim;
  if (dim != 2 && dim != 3) throw InputError(source + ": mesh dimension must be 2 or 3");
  const int ne = mesh.num_elems();
  const int nn = mesh.num_nodes();
  if (ne == 0) throw InputError(source + ": the mesh contains no elements");
  if (mesh.elems.size() != static_cast<std::size_t>(ne) * (dim + 1))
    throw InputError(source + ": element connectivity has a wrong length");
  if (mesh.elem_region.size() != static_cast<std::size_t>(ne))
    throw InputError(source + ": element region list has a wrong length");
  for (double x : mesh.X)
    if (!std::isfinite(x)) throw InputError(source + ": a node coordinate is not finite");
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a <= dim; ++a) {
      const int n = mesh.elems[static_cast<std::size_t>(e) * (dim + 1) + a];
      if (n < 0 || n >= nn)
        throw InputError(source + ": element " + std::to_string(e) + " refers to node " +
                         std::to_string(n) + ", which does not exist (" + std::to_string(nn) +
                         " nodes)");
    }
  std::vector<double> meas(ne);
  double mean = 0;
  for (int e = 0; e < ne; ++e) {
    meas[e] = signed_measure(mesh, e);
    mean += std::abs(meas[e]);
  }
  // Finite coordinates can still overflow (|x| ~ 1e200): NaN or infinite areas would pass the
  // test below.
  if (!std::isfinite(mean))
    throw InputError(source + ": element " + (dim == 2 ? "areas" : "volumes") +
                     " overflow (node coordinates are too large)");
  mean /= ne;
  const double tol = 1e-12 * mean;
  const char* what = dim == 2 ? "area" : "volume";
  for (int e = 0; e < ne; ++e) {
    const bool zero = std::abs(meas[e]) <= tol;
    const bool inverted = !zero && meas[e] < 0;
    if (!zero && !inverted) continue;
    const int r = mesh.elem_region[e];
    const std::string rname = (r >= 0 && r < static_cast<int>(mesh.region_names.size()))
                                  ? mesh.region_names[r]
                                  : std::to_string(r);
    const auto c = centroid(mesh, e);
    std::string msg = source + ": element " + std::to_string(e) + " (";
    if (elem_tags && static_cast<std::size_t>(e) < elem_tags->size())
      msg += "Gmsh element " + std::to_string((*elem_tags)[e]) + ", ";
    msg += "region '" + rname + "', centroid (" + fmt(c[0]) + ", " + fmt(c[1]);
    if (dim == 3) msg += ", " + fmt(c[2]);
    msg += ")) ";
    if (inverted) {
      msg += "is inverted (signed " + std::string(what) + " " + fmt(meas[e]) + ")";
      msg += dim == 2 ? "; triangles must be counter-clockwise (in Gmsh: orient the curve loop "
                        "counter-clockwise or use 'ReverseMesh Surface{...};')"
                      : "; tetrahedra must have positive volume (in Gmsh: 'ReverseMesh "
                        "Volume{...};')";
    } else {
      msg += "has zero " + std::string(what) + " (signed " + what + " " + fmt(meas[e]) +
             ", mean |" + what + "| " + fmt(mean) + ")";
    }
    throw InputError(msg);
  }
}

}  // namespace mesh_detail

using namespace mesh_detail;

void check_elements(const HostMesh& mesh, const std::string& source) {
  check_elements_impl(mesh, source, nullptr);
}

// ---------------------------------------------------------------------------------------------
// Quality

namespace {

double dist(const double* a, const double* b, int dim) {
  double s = 0;
  for (int k = 0; k < dim; ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(s);
}

std::array<double, 3> cross(const std::array<double, 3>& u, const std::array<double, 3>& v) {
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}

double norm(const std::array<double, 3>& u) {
  return std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
}

// Triangle with nodes n and signed area `meas`: lowers min_angle_deg by its interior angles and
// returns its shortest altitude (2 A / longest edge).
double triangle_angles(const HostMesh& mesh, const int* n, double meas, double lmax, double pi,
                       double& min_angle_deg) {
  const double hmin = 2.0 * std::abs(meas) / lmax;
  for (int a = 0; a < 3; ++a) {
    const double* p = &mesh.X[2 * static_cast<std::size_t>(n[a])];
    const double* p1 = &mesh.X[2 * static_cast<std::size_t>(n[(a + 1) % 3])];
    const double* p2 = &mesh.X[2 * static_cast<std::size_t>(n[(a + 2) % 3])];
    const double ux = p1[0] - p[0], uy = p1[1] - p[1];
    const double vx = p2[0] - p[0], vy = p2[1] - p[1];
    const double ang = std::atan2(std::abs(ux * vy - uy * vx), ux * vx + uy * vy);
    min_angle_deg = std::min(min_angle_deg, ang * 180.0 / pi);
  }
  return hmin;
}

// Tetrahedron with nodes n: its faces' outward normals (area-weighted, from the local face table)
// into nf, and its largest face area.
double tetrahedron_faces(const HostMesh& mesh, const int* n, std::array<std::array<double, 3>, 4>& nf) {
  double amax = 0;
  for (int f = 0; f < 4; ++f) {
    const double* x0 = &mesh.X[3 * static_cast<std::size_t>(n[kFaces3[f][0]])];
    const double* x1 = &mesh.X[3 * static_cast<std::size_t>(n[kFaces3[f][1]])];
    const double* x2 = &mesh.X[3 * static_cast<std::size_t>(n[kFaces3[f][2]])];
    const std::array<double, 3> u{x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]};
    const std::array<double, 3> v{x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2]};
    nf[f] = cross(u, v);
    amax = std::max(amax, 0.5 * norm(nf[f]));
  }
  return amax;
}

// Tetrahedron with nodes n and signed volume `meas`: lowers min_angle_deg by its dihedral angles
// (unless angles is false) and returns its shortest altitude (3 V / largest face area).
double tetrahedron_angles(const HostMesh& mesh, const int* n, double meas, double pi, double& min_angle_deg,
                          bool angles = true) {
  std::array<std::array<double, 3>, 4> nf;
  const double amax = tetrahedron_faces(mesh, n, nf);
  const double hmin = amax > 0 ? 3.0 * std::abs(meas) / amax : 0.0;
  for (int f = 0; f < 4 && angles; ++f)
    for (int g = f + 1; g < 4; ++g) {
      const double nn = norm(nf[f]) * norm(nf[g]);
      double c = nn > 0 ? (nf[f][0] * nf[g][0] + nf[f][1] * nf[g][1] + nf[f][2] * nf[g][2]) / nn : 1.0;
      c = std::max(-1.0, std::min(1.0, c));
      const double dihedral = pi - std::acos(c);
      min_angle_deg = std::min(min_angle_deg, dihedral * 180.0 / pi);
    }
  return hmin;
}

// An element's edges summed into edge_sum (and counted) and its shortest altitude; its angles
// lower min_angle_deg where `angles`.
double element_sizes(const HostMesh& mesh, int e, double pi, bool angles, double& edge_sum, std::size_t& edge_count,
                     double& min_angle_deg, double& meas, double& lmax) {
  const int dim = mesh.dim, npe = dim + 1;
  const int* n = &mesh.elems[static_cast<std::size_t>(e) * npe];
  meas = signed_measure(mesh, e);
  lmax = 0;
  for (int a = 0; a < npe; ++a)
    for (int b = a + 1; b < npe; ++b) {
      const double l = dist(&mesh.X[static_cast<std::size_t>(n[a]) * dim], &mesh.X[static_cast<std::size_t>(n[b]) * dim], dim);
      lmax = std::max(lmax, l);
      edge_sum += l;
      ++edge_count;
    }
  if (dim == 3) return tetrahedron_angles(mesh, n, meas, pi, min_angle_deg, angles);
  if (angles) return triangle_angles(mesh, n, meas, lmax, pi, min_angle_deg);
  return 2.0 * std::abs(meas) / lmax;  // (triangle_angles' altitude)
}

}  // namespace

MeshQuality mesh_quality(const HostMesh& mesh) { return mesh_quality(mesh, mesh.num_elems()); }

MeshQuality mesh_quality(const HostMesh& mesh, int elems) {
  MeshQuality q;
  const int dim = mesh.dim;
  const int ne = std::min(elems, mesh.num_elems());
  if (ne == 0 || (dim != 2 && dim != 3)) return q;
  const double pi = std::acos(-1.0);
  q.min_angle_deg = std::numeric_limits<double>::infinity();
  q.max_aspect = 0;
  q.min_size = std::numeric_limits<double>::infinity();
  q.min_measure = std::numeric_limits<double>::infinity();
  double edge_sum = 0;
  std::size_t edge_count = 0;
  for (int e = 0; e < ne; ++e) {
    double meas = 0, lmax = 0;
    const double hmin = element_sizes(mesh, e, pi, true, edge_sum, edge_count, q.min_angle_deg, meas, lmax);
    q.min_measure = std::min(q.min_measure, meas);
    q.min_size = std::min(q.min_size, hmin);
    q.max_aspect = std::max(q.max_aspect, hmin > 0 ? lmax / hmin
                                                   : std::numeric_limits<double>::infinity());
  }
  q.mean_size = edge_count ? edge_sum / static_cast<double>(edge_count) : 0.0;
  q.edge_sum = edge_sum;
  q.edge_count = static_cast<long>(edge_count);
  return q;
}

ElementSizes mesh_sizes(const HostMesh& mesh) {
  ElementSizes q;
  const int dim = mesh.dim, ne = mesh.num_elems();
  if (ne == 0 || (dim != 2 && dim != 3)) return q;
  q.min_size = std::numeric_limits<double>::infinity();
  double edge_sum = 0, no_angle = 0;
  std::size_t edge_count = 0;
  for (int e = 0; e < ne; ++e) {
    double meas = 0, lmax = 0;
    q.min_size = std::min(q.min_size, element_sizes(mesh, e, 0.0, false, edge_sum, edge_count, no_angle, meas, lmax));
  }
  q.mean_size = edge_count ? edge_sum / static_cast<double>(edge_count) : 0.0;
  return q;
}

// ---------------------------------------------------------------------------------------------
// Boundary faces

namespace {

using FaceKey = std::array<int, 3>;

FaceKey face_key(const int* nodes, int dim) {
  FaceKey k{nodes[0], nodes[1], dim == 3 ? nodes[2] : -1};
  sort_face_key(k, dim);
  return k;
}

}  // namespace

// A face is on the boundary when no other element has all its nodes and it is no side of an
// interface. Found through the elements of each node and the interface sides of each node (their
// smallest node): linear in the mesh (sorting every face cost 10 % of a 3D run's set-up).
void add_region_node_sets(HostMesh& mesh, const std::vector<std::string>& regions) {
  const int npe = mesh.dim + 1, ne = mesh.num_elems();
  for (const std::string& r : regions) {
    const int ri = mesh.region_index(r);
    if (ri < 0)
      throw InputError("node set '" + std::string(kRegionSetPrefix) + r + "': the mesh has no region '" + r +
                       "'");
    std::vector<char> in(mesh.num_nodes(), 0);
    for (int e = 0; e < ne; ++e)
      if (mesh.elem_region[e] == ri)
        for (int a = 0; a < npe; ++a) in[mesh.elems[static_cast<std::size_t>(e) * npe + a]] = 1;
    std::vector<int>& set = mesh.node_sets[kRegionSetPrefix + r];
    set.clear();
    for (int n = 0; n < mesh.num_nodes(); ++n)
      if (in[n]) set.push_back(n);
  }
}

std::vector<int> boundary_faces(const HostMesh& mesh) {
  const int dim = mesh.dim;
  const int npe = dim + 1;
  const int ne = mesh.num_elems();
  const int nn = mesh.num_nodes();
  const int ni = mesh.num_ifaces();
  std::vector<int> out;
  if (ne == 0) return out;
  const int* el = mesh.elems.data();
  for (std::size_t i = 0; i < mesh.elems.size(); ++i)
    if (el[i] < 0 || el[i] >= nn) throw InputError("boundary_faces: element node id out of range");
  // elements of each node (an element may list a node twice: then twice)
  const Csr node_elems(nn, ne * npe, [&](int i) { return el[i]; });
  // interface sides by their smallest node
  std::vector<FaceKey> side_key(static_cast<std::size_t>(2) * ni);
  for (int i = 0; i < 2 * ni; ++i) {
    side_key[i] = face_key(&mesh.ifaces[static_cast<std::size_t>(dim) * i], dim);
    if (side_key[i][0] < 0 || side_key[i][dim - 1] >= nn)
      throw InputError("boundary_faces: interface node id out of range");
  }
  const Csr node_sides(nn, 2 * ni, [&](int i) { return side_key[i][0]; });
  auto has_node = [&](int e, int n) {
    for (int a = 0; a < npe; ++a)
      if (el[static_cast<std::size_t>(e) * npe + a] == n) return true;
    return false;
  };
  for (int e = 0; e < ne; ++e)
    for (int f = 0; f < npe; ++f) {
      int nodes[3] = {-1, -1, -1};
      for (int k = 0; k < dim; ++k) nodes[k] = el[static_cast<std::size_t>(e) * npe + face_node(dim, f, k)];
      const FaceKey key = face_key(nodes, dim);
      bool single = true;
      for (int j = node_elems.off[key[0]]; single && j < node_elems.off[key[0] + 1]; ++j) {
        const int other = node_elems.item[j] / npe;
        if (other == e) continue;
        bool all = true;
        for (int k = 1; k < dim && all; ++k) all = has_node(other, key[k]);
        single = !all;
      }
      for (int j = node_sides.off[key[0]]; single && j < node_sides.off[key[0] + 1]; ++j)
        single = side_key[node_sides.item[j]] != key;
      if (single) out.insert(out.end(), nodes, nodes + dim);
    }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Dispatch

namespace {

// Cells along one axis (a double: the memory check comes before the per-axis limit of to_cells).
double cells_for(const std::string& kind, const char* axis, int given, double length, double h) {
  if (given > 0) return given;
  if (given < 0)
    throw InputError("mesh '" + kind + "': cells along " + axis + " must be positive (got " +
                     std::to_string(given) + ")");
  if (!(h > 0))
    throw InputError("mesh '" + kind + "': give either cells or a positive element_size");
  if (!(length > 0))
    throw InputError("mesh '" + kind + "': size along " + axis + " must be positive");
  return std::max(1.0, std::ceil(length / h - 1e-9));
}

int to_cells(const std::string& kind, const char* axis, double n, double length, double h) {
  if (!(n <= 1e7) && !(h > 0))
    throw InputError("mesh.cells along " + std::string(axis) + " = " + fmt(n) + " for generator '" + kind +
                     "' is above the limit of 1e+07 cells per direction");
  if (!(n <= 1e7))
    throw InputError(
        "mesh.element_size = " + fmt(h) + " m makes " + fmt(n) + " cells along " + axis + " (size " +
        fmt(length) + " m) for generator '" + kind +
        "'; the limit is 1e+07 cells per direction: give mesh.element_size >= " + fmt(length / 1e7));
  return std::max(1, static_cast<int>(n));
}

// What asked for a block generator's cells, for the memory check's message.
std::string block_request(const MeshSpec& spec, const double* n, int dim) {
  std::string cells = fmt(n[0]);
  for (int k = 1; k < dim; ++k) cells += " x " + fmt(n[k]);
  if (spec.cells[0] > 0) return "mesh.cells = " + cells;
  return "mesh.element_size = " + fmt(spec.element_size) + " m (" + cells + " cells)";
}

}  // namespace

HostMesh build_mesh(const MeshSpec& spec, int dim) {
  if (dim != 2 && dim != 3)
    throw InputError("mesh: dimension must be 2 or 3 (got " + std::to_string(dim) + ")");
  auto need_dim = [&](int d) {
    if (d != dim)
      throw InputError("mesh kind '" + spec.kind + "' is " + std::to_string(d) +
                       "D but the case is " + std::to_string(dim) + "D");
  };
  const std::string region = spec.region.empty() ? std::string("body") : spec.region;
  // the memory checks before meshing count the refined mesh (mesh.refine)
  const double rf = refine_factor(dim, spec.refine);
  const std::string refined = spec.refine > 0 ? ", refined " + std::to_string(spec.refine) + " times" : "";
  if (spec.kind == "file") {
    if (spec.file.empty()) throw InputError("mesh kind 'file' needs a file name");
    return read_gmsh(spec.file, dim, spec.element_size);
  }
  if (spec.kind == "rectangle") {
    need_dim(2);
    const double cx = cells_for(spec.kind, "x", spec.cells[0], spec.size[0], spec.element_size);
    const double cy = cells_for(spec.kind, "y", spec.cells[1], spec.size[1], spec.element_size);
    const double n[2] = {cx, cy};
    check_fits_in_memory(4.0 * cx * cy * rf, 2, block_request(spec, n, 2) + refined,
                         spec.cells[0] > 0 ? 0.0 : spec.element_size, "mesh.element_size",
                         4.0 * spec.size[0] * spec.size[1] * rf);
    const int nx = to_cells(spec.kind, "x", cx, spec.size[0], spec.element_size);
    const int ny = to_cells(spec.kind, "y", cy, spec.size[1], spec.element_size);
    return generate_crossed_rectangle(spec.origin[0], spec.origin[1], spec.size[0], spec.size[1],
                                      nx, ny, region);
  }
  if (spec.kind == "box") {
    need_dim(3);
    const double cx = cells_for(spec.kind, "x", spec.cells[0], spec.size[0], spec.element_size);
    const double cy = cells_for(spec.kind, "y", spec.cells[1], spec.size[1], spec.element_size);
    const double cz = cells_for(spec.kind, "z", spec.cells[2], spec.size[2], spec.element_size);
    const double n[3] = {cx, cy, cz};
    check_fits_in_memory(6.0 * cx * cy * cz * rf, 3, block_request(spec, n, 3) + refined,
                         spec.cells[0] > 0 ? 0.0 : spec.element_size, "mesh.element_size",
                         6.0 * spec.size[0] * spec.size[1] * spec.size[2] * rf);
    const int nx = to_cells(spec.kind, "x", cx, spec.size[0], spec.element_size);
    const int ny = to_cells(spec.kind, "y", cy, spec.size[1], spec.element_size);
    const int nz = to_cells(spec.kind, "z", cz, spec.size[2], spec.element_size);
    return generate_box(spec.origin, spec.size, nx, ny, nz, region);
  }
  if (spec.kind == "disc") {
    need_dim(2);
    const double pi = std::acos(-1.0), R = spec.radius, h = spec.element_size;
    if (R > 0 && h > 0 && h <= R)
      check_fits_in_memory(estimate_gmsh_elements(2, pi * R * R, h) * rf, 2,
                           "mesh.element_size = " + fmt(h) + " m (disc of radius " + fmt(R) + " m" + refined + ")",
                           h, "mesh.element_size", estimate_gmsh_elements(2, pi * R * R, 1.0) * rf);
    return generate_disc(spec.origin[0], spec.origin[1], spec.radius, spec.element_size, region,
                         spec.diameter[0], spec.diameter[1], spec.symmetric);
  }
  if (spec.kind == "sphere") {
    need_dim(3);
    const double pi = std::acos(-1.0), R = spec.radius, h = spec.element_size;
    if (R > 0 && h > 0 && h <= R)
      check_fits_in_memory(estimate_gmsh_elements(3, 4.0 / 3.0 * pi * R * R * R, h) * rf, 3,
                           "mesh.element_size = " + fmt(h) + " m (sphere of radius " + fmt(R) + " m" + refined + ")",
                           h, "mesh.element_size", estimate_gmsh_elements(3, 4.0 / 3.0 * pi * R * R * R, 1.0) * rf);
    return generate_sphere(spec.origin, spec.radius, spec.element_size, region, spec.mesher);
  }
  if (spec.kind == "particles") {  // many particles, each its own body (particles.cpp)
    need_dim(3);
    return generate_particles(spec.particles, spec.element_size, spec.region);
  }
  if (spec.kind == "grains") {
    const double pi = std::acos(-1.0), h = spec.element_size;
    const double measure = dim == 3               ? spec.size[0] * spec.size[1] * spec.size[2]
                           : spec.shape == "disc" ? pi * spec.radius * spec.radius
                                                  : spec.size[0] * spec.size[1];
    if (h > 0 && measure > 0)
      check_fits_in_memory(estimate_gmsh_elements(dim, measure, h) * rf, dim,
                           "mesh.element_size = " + fmt(h) + " m (grains" + refined + ")", h, "mesh.element_size",
                           estimate_gmsh_elements(dim, measure, 1.0) * rf);
    return dim == 3 ? generate_grains_3d(spec) : generate_grains(spec);
  }
  throw InputError("mesh: unknown kind '" + spec.kind +
                   "' (expected file, rectangle, disc, box, sphere, particles or grains)");
}

}  // namespace fdem
