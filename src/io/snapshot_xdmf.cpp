// SnapshotWriter::write_xdmf: snapshots.xdmf (XDMF 3), a temporal collection of the frames in
// snapshots.h5 (layout: src/io/snapshot_writer.cpp), each a spatial collection of the grids "bulk"
// and "interfaces".

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>

#include "io/output.hpp"
#include "io/snapshot_internal.hpp"

namespace fdem {

namespace fs = std::filesystem;
using snapshot::step_name;

namespace {

// Shortest of %.15g / %.17g that reads back to the same double.
std::string fmt_double(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.15g", v);
  if (std::strtod(buf, nullptr) != v) std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string item(const std::string& dims, bool is_int, const std::string& ds) {
  return std::string("<DataItem Dimensions=\"") + dims + "\" NumberType=\"" +
         (is_int ? "Int" : "Float") + "\" Precision=\"" + (is_int ? "4" : "8") +
         "\" Format=\"HDF\">" + snapshot::kH5Name + ":" + ds + "</DataItem>";
}

// Lines of a uniform grid sit at 8 spaces, their children deeper.
std::string attr(const std::string& name, const char* type, const char* center,
                 const std::string& dims, bool is_int, const std::string& ds) {
  return std::string("          <Attribute Name=\"") + name + "\" AttributeType=\"" + type +
         "\" Center=\"" + center + "\">\n            " + item(dims, is_int, ds) +
         "\n          </Attribute>\n";
}

// One frame's view of the mesh sizes, as the text of the XDMF.
struct Frame {
  int dim;
  std::string nn, ne, ni, npe;
  std::string g;     // its group, "/step_NNNNNNNN"
  std::string t;     // its time
  std::string geom;  // its Geometry element (the current coordinates)
  bool frag;         // whether it has a fragment field
  bool imat, istrength;  // whether the file has /mesh/interface_material, /mesh/strength_factor
};

// The grid "bulk": triangles/tetrahedra with the node and cell fields.
void bulk_grid(std::ostringstream& o, const Frame& f) {
  const char* bulk_topo = f.dim == 2 ? "Triangle" : "Tetrahedron";
  o << "        <Grid Name=\"bulk\" GridType=\"Uniform\">\n"
    << "          <Time Value=\"" << f.t << "\"/>\n"
    << "          <Topology TopologyType=\"" << bulk_topo << "\" NumberOfElements=\"" << f.ne
    << "\" NodesPerElement=\"" << f.npe << "\">\n"
    << "            " << item(f.ne + " " + f.npe, true, "/mesh/elements") << "\n"
    << "          </Topology>\n"
    << f.geom
    << attr("displacement", "Vector", "Node", f.nn + " 3", false, f.g + "/displacement")
    << attr("velocity", "Vector", "Node", f.nn + " 3", false, f.g + "/velocity")
    << attr("stress", "Tensor6", "Cell", f.ne + " 6", false, f.g + "/stress")
    << attr("von_mises", "Scalar", "Cell", f.ne, false, f.g + "/von_mises")
    << attr("region", "Scalar", "Cell", f.ne, true, "/mesh/region");
  if (f.frag) o << attr("fragment", "Scalar", "Cell", f.ne, true, f.g + "/fragment");
  o << "        </Grid>\n";
}

// The grid "interfaces": polylines/triangles on the current A-side nodes, with their damage.
void interface_grid(std::ostringstream& o, const Frame& f) {
  o << "        <Grid Name=\"interfaces\" GridType=\"Uniform\">\n"
    << "          <Time Value=\"" << f.t << "\"/>\n";
  if (f.dim == 2) {
    o << "          <Topology TopologyType=\"Polyline\" NumberOfElements=\"" << f.ni
      << "\" NodesPerElement=\"2\">\n";
  } else {
    o << "          <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << f.ni
      << "\" NodesPerElement=\"3\">\n";
  }
  o << "            " << item(f.ni + " " + std::to_string(f.dim), true, "/mesh/interfaces")
    << "\n"
    << "          </Topology>\n"
    << f.geom << attr("damage", "Scalar", "Cell", f.ni, false, f.g + "/damage");
  if (f.imat) o << attr("interface_material", "Scalar", "Cell", f.ni, true, "/mesh/interface_material");
  if (f.istrength) o << attr("strength_factor", "Scalar", "Cell", f.ni, false, "/mesh/strength_factor");
  o << "        </Grid>\n";
}

}  // namespace

void SnapshotWriter::write_xdmf() const {
  Frame fr;
  fr.dim = dim_;
  fr.nn = std::to_string(nn_);
  fr.ne = std::to_string(ne_);
  fr.ni = std::to_string(ni_);
  fr.npe = std::to_string(dim_ + 1);
  fr.imat = imat_;
  fr.istrength = istrength_;

  std::ostringstream o;
  o << "<?xml version=\"1.0\" ?>\n"
    << "<Xdmf Version=\"3.0\">\n"
    << "  <Domain>\n"
    << "    <Grid Name=\"fdem\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (size_t f = 0; f < steps_.size(); ++f) {
    fr.g = "/" + step_name(steps_[f]);
    fr.t = fmt_double(times_[f]);
    fr.geom = "          <Geometry GeometryType=\"XYZ\">\n            " +
              item(fr.nn + " 3", false, fr.g + "/coordinates") + "\n          </Geometry>\n";
    fr.frag = f < fragment_.size() && fragment_[f];
    o << "      <Grid Name=\"" << step_name(steps_[f])
      << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
      << "        <Time Value=\"" << fr.t << "\"/>\n";
    bulk_grid(o, fr);
    if (ni_ > 0) interface_grid(o, fr);
    o << "      </Grid>\n";
  }
  o << "    </Grid>\n"
    << "  </Domain>\n"
    << "</Xdmf>\n";
  write_file_atomic((fs::path(dir_) / snapshot::kXdmfName).string(), o.str());
}

}  // namespace fdem
