#pragma once
// Fragment analysis of a run (kernels/fragments.hpp): connected components of the bulk elements
// over shared nodes and intact interfaces, with per-fragment masses and a mass distribution.
// A full pass over the mesh: call it on output intervals only.
#include <array>
#include <string>
#include <vector>

#include "kernels/fragments.hpp"
#include "kernels/model.hpp"

namespace fdem {

struct FragmentStats {
  int count = 0;                // number of fragments
  int single_element = 0;       // fragments made of one element
  int rounds = 0;               // hook rounds the labelling needed
  double total_mass = 0;        // sum of the fragment masses (kg; 2D: per the thickness)
  double largest_mass = 0;      // kg
  double largest_fraction = 0;  // largest_mass / total_mass
  // bin b: fragments with mass fraction in [10^-(b+1), 10^-b) (bin 0 includes 1, the last bin
  // everything below 10^-(kFragmentBins-1)): their number and their summed mass fraction
  std::array<double, kFragmentBins> bin_count{}, bin_mass_fraction{};
  // Lower edge of bin b as text: "1e-1", ..., "1e-7", and "0" for the last bin.
  static std::string bin_name(int b);
};

template <int D>
class FragmentAnalysis {
 public:
  explicit FragmentAnalysis(const Model<D>& m);
  // Labels the fragments of the current state and returns their statistics.
  FragmentStats compute(const Model<D>& m);
  // After compute(): fragment id of every element (host copy) and the mass of every fragment.
  void element_ids(std::vector<int>& out) const;
  std::vector<double> masses() const;
  const FragmentStats& last() const { return last_; }

 private:
  Kokkos::View<int*> par_, lab_, used_, root_id_, elem_frag_;
  Kokkos::View<double*> emass_;
  Kokkos::View<double* [2]> fstat_;
  FragmentStats last_;
};

extern template class FragmentAnalysis<2>;
extern template class FragmentAnalysis<3>;

}  // namespace fdem
