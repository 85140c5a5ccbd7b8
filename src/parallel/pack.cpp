// A part, or a run's state, as bytes and back (src/parallel/decompose.hpp: pack_submesh,
// pack_state): what process 0 sends each process of a run over several processes.
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "parallel/decompose.hpp"

namespace fdem {

namespace {

// Where the bytes go: memory (pack_*) or a file (write_mesh_file), in the same order.
struct ByteSink {
  std::vector<char> bytes;
  void write(const char* p, size_t n) { bytes.insert(bytes.end(), p, p + n); }
};
struct FileSink {
  std::FILE* f;
  bool ok = true;
  void write(const char* p, size_t n) { ok = ok && (n == 0 || std::fwrite(p, 1, n, f) == n); }
};

// The byte stream of pack_submesh: plain values, strings, vectors and string-keyed maps of them,
// in order; a vector of plain values in one piece.
template <class Sink>
class Packer {
 public:
  Sink sink;
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>, "plain values");
    sink.write(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void put(const std::string& v) {
    put(static_cast<long long>(v.size()));
    sink.write(v.data(), v.size());
  }
  template <class T>
  void put(const std::vector<T>& v) {
    put(static_cast<long long>(v.size()));
    if constexpr (std::is_trivially_copyable_v<T>) {
      sink.write(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    } else {
      for (const auto& x : v) put(x);
    }
  }
  template <class T>
  void put(const std::map<std::string, T>& v) {
    put(static_cast<long long>(v.size()));
    for (const auto& [k, x] : v) {
      put(k);
      put(x);
    }
  }
};

// Where the bytes come from: memory (unpack_*) or a file (read_mesh_file), with how many are left
// (so that a damaged count is refused before anything is allocated for it).
struct ByteSource {
  const std::vector<char>& b;
  size_t at = 0;
  size_t left() const { return b.size() - at; }
  bool read(void* p, size_t n) {
    if (n > left()) return false;
    if (n > 0) std::memcpy(p, b.data() + at, n);  // (an empty vector's data() may be null: no memcpy)
    at += n;
    return true;
  }
};
struct FileSource {
  std::FILE* f;
  size_t rest;
  size_t left() const { return rest; }
  bool read(void* p, size_t n) {
    if (n > rest || (n > 0 && std::fread(p, 1, n, f) != n)) return false;
    rest -= n;
    return true;
  }
};

template <class Source>
class Unpacker {
 public:
  explicit Unpacker(Source src) : src_(std::move(src)) {}
  template <class T>
  void get(T& v) {
    static_assert(std::is_trivially_copyable_v<T>, "plain values");
    take(&v, sizeof(T));
  }
  void get(std::string& v) {
    v.resize(count(1));
    take(v.data(), v.size());
  }
  template <class T>
  void get(std::vector<T>& v) {
    if constexpr (std::is_trivially_copyable_v<T>) {
      v.resize(count(sizeof(T)));
      take(v.data(), v.size() * sizeof(T));
    } else {
      v.resize(count(1));
      for (auto& x : v) get(x);
    }
  }
  template <class T>
  void get(std::map<std::string, T>& v) {
    v.clear();
    const size_t n = count(1);
    for (size_t i = 0; i < n; ++i) {
      std::string k;
      get(k);
      get(v[k]);
    }
  }
  bool done() const { return src_.left() == 0; }

 private:
  // a count of items of at least `least` bytes each, checked against what is left
  size_t count(size_t least) {
    long long n = 0;
    get(n);
    if (n < 0 || static_cast<unsigned long long>(n) > src_.left() / least)
      throw InputError("unpack_submesh: a count beyond the end of the data (damaged)");
    return static_cast<size_t>(n);
  }
  void take(void* p, size_t n) {
    if (!src_.read(p, n)) throw InputError("unpack_submesh: the data ends early (damaged)");
  }
  Source src_;
};

// Both directions over one list of the fields (f: Packer::put or Unpacker::get).
template <class M, class F>
void mesh_fields(M& m, F&& f) {
  f(m.dim);
  f(m.X);
  f(m.elems);
  f(m.elem_region);
  f(m.region_names);
  f(m.node_sets);
  f(m.face_sets);
  f(m.iface_sets);
  f(m.ifaces);
  f(m.iface_elems);
  f(m.node_origin);
  f(m.warnings);
  f(m.bodies);
  f(m.owned_nodes);
  f(m.owned_elems);
  f(m.owned_ifaces);
  f(m.bulk_elems);
  f(m.whole_set_size);
  f(m.outer_faces);
  f(m.pieces);
  f(m.whole_min_size);
  f(m.iface_ids);
}

template <class S, class F>
void submesh_fields(S& s, F&& f) {
  f(s.part);
  f(s.parts);
  f(s.whole_nodes);
  f(s.whole_elems);
  f(s.whole_ifaces);
  mesh_fields(s.mesh, f);
  f(s.contact_reach);
  f(s.cut_x);
  f(s.node_global);
  f(s.elem_global);
  f(s.iface_global);
  f(s.neighbours);
  f(s.send);
  f(s.recv);
  f(s.inert_ghosts);
}

// Packed and unpacked over one list of fields (fields(x, f): f is Packer::put or Unpacker::get);
// unpacking throws InputError naming `what` when the bytes do not unpack exactly.
template <class T, class Fields>
std::vector<char> pack_fields(const T& x, Fields&& fields) {
  Packer<ByteSink> p;
  fields(x, [&](const auto& v) { p.put(v); });
  return std::move(p.sink.bytes);
}

template <class T, class Source, class Fields>
T unpack_from(Source src, Fields&& fields, const char* what) {
  T x;
  Unpacker<Source> u(std::move(src));
  fields(x, [&](auto& v) { u.get(v); });
  if (!u.done()) throw InputError(std::string(what) + ": data left over (damaged)");
  return x;
}

template <class T, class Fields>
T unpack_fields(const std::vector<char>& bytes, Fields&& fields, const char* what) {
  return unpack_from<T>(ByteSource{bytes}, fields, what);
}

const auto submesh_list = [](auto& s, auto&& f) { submesh_fields(s, f); };
const auto mesh_list = [](auto& m, auto&& f) { mesh_fields(m, f); };
const auto lists_list = [](auto& l, auto&& f) {
  f(l.neighbours);
  f(l.send);
};
const auto state_list = [](auto& s, auto&& f) {
  f(s.f64);
  f(s.i64);
  f(s.str);
  f(s.file);
};

}  // namespace

std::vector<char> pack_submesh(const SubMesh& s) { return pack_fields(s, submesh_list); }
SubMesh unpack_submesh(const std::vector<char>& bytes) {
  return unpack_fields<SubMesh>(bytes, submesh_list, "unpack_submesh");
}
std::vector<char> pack_lists(const PartLists& l) { return pack_fields(l, lists_list); }
PartLists unpack_lists(const std::vector<char>& bytes) {
  return unpack_fields<PartLists>(bytes, lists_list, "unpack_lists");
}
std::vector<char> pack_mesh(const HostMesh& m) { return pack_fields(m, mesh_list); }
HostMesh unpack_mesh(const std::vector<char>& bytes) { return unpack_fields<HostMesh>(bytes, mesh_list, "unpack_mesh"); }
std::vector<char> pack_state(const StateArrays& s) { return pack_fields(s, state_list); }
StateArrays unpack_state(const std::vector<char>& bytes) {
  return unpack_fields<StateArrays>(bytes, state_list, "unpack_state");
}

long write_mesh_file(std::FILE* f, const HostMesh& m) {
  Packer<FileSink> p{FileSink{f}};
  const long start = std::ftell(f);
  mesh_list(m, [&](const auto& v) { p.put(v); });
  if (!p.sink.ok || std::fflush(f) != 0) return -1;
  return std::ftell(f) - start;
}

HostMesh read_mesh_file(std::FILE* f, long bytes) {
  return unpack_from<HostMesh>(FileSource{f, static_cast<size_t>(bytes)}, mesh_list, "read_mesh_file");
}

}  // namespace fdem
