#include "solver/fragment_analysis.hpp"

namespace fdem {

std::string FragmentStats::bin_name(int b) {
  if (b >= kFragmentBins - 1) return "0";
  return "1e-" + std::to_string(b + 1);
}

template <int D>
FragmentAnalysis<D>::FragmentAnalysis(const Model<D>& m)
    : par_("fdem::fragments::par", m.nn),
      lab_("fdem::fragments::lab", m.nn),
      used_("fdem::fragments::used", m.nn),
      root_id_("fdem::fragments::root_id", m.nn),
      elem_frag_("fdem::fragments::elem", m.ne),
      emass_("fdem::fragments::emass", m.ne) {
  mark_used<D>(m, used_);
  element_masses<D>(m, emass_);
}

template <int D>
FragmentStats FragmentAnalysis<D>::compute(const Model<D>& m) {
  FragmentStats s;
  s.rounds = label_components<D>(m, par_, lab_);
  s.count = fragment_ids<D>(m, lab_, used_, root_id_, elem_frag_);
  if (static_cast<int>(fstat_.extent(0)) != s.count)
    fstat_ = Kokkos::View<double* [2]>("fdem::fragments::stat", s.count);
  fragment_masses(elem_frag_, emass_, fstat_);
  double largest = 0;
  const FragmentSums sums = fragment_statistics(fstat_, s.count, largest);
  s.total_mass = sums.v[0];
  s.single_element = static_cast<int>(sums.v[1]);
  s.largest_mass = s.count > 0 ? largest : 0.0;
  s.largest_fraction = s.total_mass > 0 ? s.largest_mass / s.total_mass : 0.0;
  for (int b = 0; b < kFragmentBins; ++b) {
    s.bin_count[b] = sums.v[2 + b];
    s.bin_mass_fraction[b] = s.total_mass > 0 ? sums.v[2 + kFragmentBins + b] / s.total_mass : 0.0;
  }
  last_ = s;
  return s;
}

template <int D>
void FragmentAnalysis<D>::element_ids(std::vector<int>& out) const {
  auto h = Kokkos::create_mirror_view(elem_frag_);
  Kokkos::deep_copy(h, elem_frag_);
  out.assign(h.data(), h.data() + h.extent(0));
}

template <int D>
std::vector<double> FragmentAnalysis<D>::masses() const {
  auto h = Kokkos::create_mirror_view(fstat_);
  Kokkos::deep_copy(h, fstat_);
  std::vector<double> out(h.extent(0));
  for (size_t f = 0; f < out.size(); ++f) out[f] = h(f, 0);
  return out;
}

template class FragmentAnalysis<2>;
template class FragmentAnalysis<3>;

}  // namespace fdem
