// A part, or a run's state, as bytes and back (src/parallel/decompose.hpp: pack_submesh,
// pack_state): what process 0 sends each process of a run over several processes.
#include <cstring>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "common/error.hpp"
#include "parallel/decompose.hpp"

namespace fdem {

namespace {

// The byte stream of pack_submesh: plain values, strings, vectors and string-keyed maps of them,
// in order; a vector of plain values in one piece.
class Packer {
 public:
  std::vector<char> bytes;
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>, "plain values");
    const char* p = reinterpret_cast<const char*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  void put(const std::string& v) {
    put(static_cast<long long>(v.size()));
    bytes.insert(bytes.end(), v.begin(), v.end());
  }
  template <class T>
  void put(const std::vector<T>& v) {
    put(static_cast<long long>(v.size()));
    if constexpr (std::is_trivially_copyable_v<T>) {
      const char* p = reinterpret_cast<const char*>(v.data());
      bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
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

class Unpacker {
 public:
  explicit Unpacker(const std::vector<char>& b) : b_(b) {}
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
  bool done() const { return at_ == b_.size(); }

 private:
  // a count of items of at least `least` bytes each, checked against what is left
  size_t count(size_t least) {
    long long n = 0;
    get(n);
    if (n < 0 || static_cast<unsigned long long>(n) > (b_.size() - at_) / least)
      throw InputError("unpack_submesh: a count beyond the end of the data (damaged)");
    return static_cast<size_t>(n);
  }
  void take(void* p, size_t n) {
    if (n > b_.size() - at_) throw InputError("unpack_submesh: the data ends early (damaged)");
    if (n == 0) return;  // (an empty vector's data() may be null: no memcpy)
    std::memcpy(p, b_.data() + at_, n);
    at_ += n;
  }
  const std::vector<char>& b_;
  size_t at_ = 0;
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
  Packer p;
  fields(x, [&](const auto& v) { p.put(v); });
  return std::move(p.bytes);
}

template <class T, class Fields>
T unpack_fields(const std::vector<char>& bytes, Fields&& fields, const char* what) {
  T x;
  Unpacker u(bytes);
  fields(x, [&](auto& v) { u.get(v); });
  if (!u.done()) throw InputError(std::string(what) + ": data left over (damaged)");
  return x;
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

}  // namespace fdem
