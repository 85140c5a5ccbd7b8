#pragma once
// Fragments of a run over several processes, labelled where the elements are (issue 49;
// docs/parallel.md, "Fragments over processes"). No process holds the whole mesh for it, and no
// interface history travels.
//
// Each process labels the components of its own part on the device as one process labels the
// whole mesh (kernels/fragments.hpp: its elements and interfaces, the ghosts' included, whose
// histories are the owners' to the bit): each local component is a "token". Every link of the
// whole mesh (an element joining its nodes, an intact interface joining its sides) is labelled by
// the process that owns its element (its side-A element), and a node two such links of different
// processes share is an own node of one that the other holds as an exchanged ghost, or an
// exchanged ghost of both. So each process sends its own nodes' tokens along the step's exchange
// lists, and each exchanged ghost gives an edge (its token here, the owner, the owner's token),
// each edge once. Process 0 gathers per token its own elements' mass and count and its smallest
// whole-mesh node index, and the edges, and joins the tokens (union-find). A class of tokens with
// own elements is a fragment, numbered in order of its smallest node index as on one process (a
// class without own elements anywhere is a ghost's partial view: dropped). Bytes to process 0 per
// labelling: 24 per token and per edge (an intact body: one token per process and a few edges),
// against 104 per interface when process 0 gathered every history.
//
// The initial bodies (several particles: bodies.csv) are labelled once, the same way on the host
// with every interface joining its sides, and numbered in order of their first element.
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "solver/fragment_analysis.hpp"
#include "solver/fragment_bodies.hpp"
#include "solver/simulation.hpp"

namespace fdem {

// Tokens of every process joined into classes through their edges (process 0). `all`: every
// process's buffer one after the other: [tokens, edges, then `width` values per token, then per
// edge (its token, another process, that process's token)]. On return `values` holds every token's values
// (width each, in process order), `offset` each process's first token (processes + 1 entries) and
// the result is every token's class representative (the smallest token of its class).
std::vector<int> join_tokens(const std::vector<double>& all, int processes, int width,
                             std::vector<double>& values, std::vector<int>& offset);

// The classes numbered 0..n-1 in order of their smallest `key` (column `key_col` of `values`,
// width `width`, the smallest over the class), keeping only the classes whose column `count_col`
// sums above 0 (those holding own elements). Returns every token's class number (-1: dropped) and
// sets n.
std::vector<int> number_classes(const std::vector<int>& rep, const std::vector<double>& values, int width,
                                int key_col, int count_col, int& n);

// Pieces of fragments where their material was at the start: an element, or a process's part of a
// fragment. Per piece: its fragment, its mass, the sum of mass x reference centroid (3 per piece),
// and the box of its elements' reference centroids (3 + 3 per piece).
struct FragmentPieces {
  std::vector<int> frag;
  std::vector<double> mass, moment, lo, hi;
  void add(int f, double m, const double* mc, const double* l, const double* h);
};

// summary.json fragments.largest: the ten largest fragments (by `masses`, every fragment's) with
// their share of the whole mass, mass-weighted reference centroid and box of their elements'
// reference centroids (a fracture pattern is read from these: halves split through an axis, caps,
// cones).
nlohmann::json largest_fragments(const FragmentPieces& p, const std::vector<double>& masses, int dim);

template <int D>
class PartFragments {
 public:
  // Collective (every process of the run): labels the initial bodies.
  explicit PartFragments(const Simulation<D>& sim);
  // Collective: labels the fragments of the present state. The statistics are process 0's (zeros
  // on the others).
  const FragmentStats& compute(const Simulation<D>& sim);
  const FragmentStats& last() const { return last_; }
  // Collective, after compute(): the fragment id of each own element (local order, the first
  // m.owned_elems() elements).
  void element_ids(std::vector<int>& ids) const;
  // Process 0, after compute(): every fragment's mass.
  const std::vector<double>& masses() const { return frag_mass_; }
  // Collective, after compute(): on process 0 the ten largest fragments (summary.json
  // fragments.largest, as largest_fragments in src/solver/run_output.cpp) and, with several initial
  // bodies, every body's fragments (else empty); null and empty on the others.
  struct Ends {
    nlohmann::json largest;
    std::vector<BodyFragments> bodies;
  };
  Ends ends(const Simulation<D>& sim) const;
  // Process 0: the number of initial bodies (0 on the others).
  int bodies() const { return bodies_; }
  // Bytes of the last compute's gathering: process 0 what it received, the others what they sent.
  double gathered_bytes() const { return gathered_bytes_; }

 private:
  const Comm& comm_;
  const bool root_;
  int own_elems_ = 0;
  Kokkos::View<int*> par_, lab_;  // the local labelling's work space and node labels
  std::vector<double> emass_;     // own elements' masses (rho V0)
  std::vector<int> node0_;        // own elements' first nodes (a labelling reads no other: no copy of
                                  // the connectivity from the device at each one)
  std::vector<int> elem_tok_;     // own element -> its token (the last compute)
  int tokens_ = 0;                // this process's tokens (the last compute)
  // process 0, the last compute: every process's first token, every token's fragment (-1: none),
  // every fragment's mass
  std::vector<int> tok_offset_, tok_frag_;
  std::vector<double> tok_vals_, frag_mass_;  // (tok_vals_: join_tokens' values, 3 per token)
  // the initial bodies: own element -> its body token; process 0: every process's first body
  // token and every body token's body
  std::vector<int> elem_body_tok_, body_offset_, body_of_tok_;
  int bodies_ = 0;
  double gathered_bytes_ = 0;
  FragmentStats last_;

  void label_bodies(const Simulation<D>& sim);
  std::vector<double> token_buffer(const Simulation<D>& sim);
  void take_classes(const std::vector<double>& all);
};

extern template class PartFragments<2>;
extern template class PartFragments<3>;

}  // namespace fdem
