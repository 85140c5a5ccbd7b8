#pragma once
// Fragments per initial body (a particle of an assembly): the bodies of the mesh at the start
// (elements joined through shared nodes or through any interface, failed or not) and, at the end,
// each body's mass, number of fragments and largest fragment's share of its mass. Fragments only
// split bodies, so every fragment lies in exactly one initial body. Output: bodies.csv and
// summary.json fragments.per_body (docs/case-format.md, "Fragment output").
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kernels/model.hpp"

namespace fdem {

struct BodyFragments {
  int elements = 0;
  double mass = 0;                 // kg (2D: per the thickness)
  int fragments = 0;               // fragments the body has broken into (1: intact)
  double largest_fraction = 0;     // largest fragment's mass / the body's mass
  double centroid[3] = {0, 0, 0};  // reference volume-weighted centroid of its elements (m)
};

// Initial body of every element (ids 0..count-1 in order of their first element), from the
// model's connectivity: host copies of its elements and interfaces. Returns the count.
template <int D>
int initial_bodies(const Model<D>& m, std::vector<int>& body);

// Per body: `body` from initial_bodies, `frag` the fragment id of every element, `frag_mass` the
// mass of every fragment, `elem_mass` and `elem_centroid` (3 per element) those of every element.
// Throws std::logic_error when a fragment spans two bodies (impossible by construction).
std::vector<BodyFragments> body_fragments(const std::vector<int>& body, int nbodies,
                                          const std::vector<int>& frag, const std::vector<double>& frag_mass,
                                          const std::vector<double>& elem_mass,
                                          const std::vector<double>& elem_centroid);

// bodies.csv: one row per body (body, elements, mass, fragments, largest_fraction, x, y, z).
void write_bodies_csv(const std::string& path, const std::vector<BodyFragments>& b, int dim);

// {"bodies", "broken" (more than one fragment), "mean_fragments", "max_fragments",
//  "mean_largest_fraction", "min_largest_fraction", "histogram": {"fragments": [1, 2, ...],
//  "bodies": [...]} (the last entry: that many fragments or more), "file"}.
nlohmann::json body_fragments_summary(const std::vector<BodyFragments>& b, const std::string& file);

// Element masses (rho V0) and volume-weighted centroids of the reference configuration (host).
template <int D>
void element_mass_centroids(const Model<D>& m, std::vector<double>& mass, std::vector<double>& centroid);

}  // namespace fdem
