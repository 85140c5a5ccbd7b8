#include "solver/ledger.hpp"

#include <memory>
#include <utility>

#include "common/error.hpp"

namespace fdem {

namespace {

// The built-in terms. Their order is that of every output (history.csv, summary.json, the
// checkpoint vector) and of the balance's sums.
std::vector<EnergyTerm> builtin_terms() {
  using S = EnergySide;
  return {
      {"kinetic", "E_kinetic [J]", S::stored, true, "node update (kernels/nodes.hpp)", &Energies::kinetic},
      {"strain", "E_strain [J]", S::stored, true, "Simulation::sample_energies (strain_energy)", &Energies::strain},
      {"interface_elastic", "E_interface [J]", S::stored, true, "Simulation::sample_energies (interface_state)",
       &Energies::interface_elastic},
      {"contact_elastic", "E_contact [J]", S::stored, true, "platen springs and contact (sample_energies)",
       &Energies::contact_elastic},
      {"fracture", "D_fracture [J]", S::dissipated, true, "Simulation::sample_energies (interface_state)",
       &Energies::fracture},
      {"damping", "D_damping [J]", S::dissipated, true, "node update; Simulation::book_energies",
       &Energies::damping},
      {"friction", "D_friction [J]", S::dissipated, true, "interfaces (interface_state), platens and contact",
       &Energies::friction},
      {"external_work", "W_external [J]", S::work, true,
       "platens, velocity BCs, gravity, point loads (book_energies)", &Energies::work_external},
  };
}

std::vector<EnergyTerm>& terms() {
  static std::vector<EnergyTerm> t = builtin_terms();
  return t;
}

size_t builtin_count() {
  static const size_t n = builtin_terms().size();
  return n;
}

// The sum of the terms on the given sides, in table order, from the first such term's value (the
// same bits as the sum written out term by term).
double sum_of(const Energies& e, EnergySide a, EnergySide b) {
  const auto& t = terms();
  double s = 0;
  bool first = true;
  for (size_t i = 0; i < t.size(); ++i) {
    if (t[i].side != a && t[i].side != b) continue;
    const double v = term_value(e, i);
    s = first ? v : s + v;
    first = false;
  }
  return s;
}

}  // namespace

const std::vector<EnergyTerm>& energy_terms() { return terms(); }

int add_energy_term(const std::string& key, const std::string& column, EnergySide side,
                    std::function<double(double, long)> sample) {
  // the names live as long as the term (a static store: the table holds C strings)
  static std::vector<std::unique_ptr<std::string>> names;
  names.push_back(std::make_unique<std::string>(key));
  const char* k = names.back()->c_str();
  names.push_back(std::make_unique<std::string>(column));
  const char* c = names.back()->c_str();
  terms().push_back({k, c, side, false, "added (add_energy_term)", nullptr, std::move(sample)});
  return static_cast<int>(terms().size() - builtin_count()) - 1;
}

void clear_added_energy_terms() { terms().resize(builtin_count()); }

double term_value(const Energies& e, size_t term) {
  const EnergyTerm& t = terms()[term];
  if (t.field) return e.*t.field;
  const size_t a = term - builtin_count();
  return a < e.added.size() ? e.added[a] : 0.0;
}

double energy_now(const Energies& e) { return sum_of(e, EnergySide::stored, EnergySide::dissipated); }

double energy_work(const Energies& e) { return sum_of(e, EnergySide::work, EnergySide::work); }

void sample_added_terms(Energies& e) {
  const auto& t = terms();
  e.added.assign(t.size() - builtin_count(), 0.0);
  for (size_t i = builtin_count(); i < t.size(); ++i) e.added[i - builtin_count()] = t[i].sample(e.time, e.step);
}

void sum_energies(Energies& e, const std::function<void(double*, int)>& sum) {
  const auto& t = terms();
  std::vector<double> v;
  for (const auto& term : t)
    if (term.summed && term.field) v.push_back(e.*term.field);
  for (double p : e.momentum) v.push_back(p);
  v.push_back(static_cast<double>(e.damaged));
  v.push_back(static_cast<double>(e.failed));
  sum(v.data(), static_cast<int>(v.size()));
  size_t j = 0;
  for (const auto& term : t)
    if (term.summed && term.field) e.*term.field = v[j++];
  for (double& p : e.momentum) p = v[j++];
  e.damaged = static_cast<long>(v[j++]);
  e.failed = static_cast<long>(v[j++]);
}

std::vector<double> energies_to_vector(const Energies& e) {
  std::vector<double> v = {e.time, static_cast<double>(e.step)};
  for (size_t i = 0; i < builtin_count(); ++i) v.push_back(term_value(e, i));
  v.insert(v.end(), {e.balance_error, e.scale, static_cast<double>(e.damaged), static_cast<double>(e.failed)});
  v.insert(v.end(), e.momentum, e.momentum + 3);
  v.insert(v.end(), e.added.begin(), e.added.end());
  return v;
}

Energies energies_from_vector(const std::vector<double>& v, const std::string& what) {
  const size_t nb = builtin_count();
  if (v.size() < kEnergyFieldCount)
    throw InputError(what + ": " + std::to_string(v.size()) + " values, expected at least " +
                     std::to_string(kEnergyFieldCount));
  Energies e;
  e.time = v[0];
  e.step = static_cast<long>(v[1]);
  const auto& t = terms();
  for (size_t i = 0; i < nb; ++i) e.*t[i].field = v[2 + i];
  e.balance_error = v[2 + nb];
  e.scale = v[3 + nb];
  e.damaged = static_cast<long>(v[4 + nb]);
  e.failed = static_cast<long>(v[5 + nb]);
  if (v.size() >= kEnergyFieldCount + 3)
    for (int k = 0; k < 3; ++k) e.momentum[k] = v[kEnergyFieldCount + k];
  if (v.size() > kEnergyFieldCount + 3) e.added.assign(v.begin() + kEnergyFieldCount + 3, v.end());
  return e;
}

std::vector<std::string> energy_columns() {
  std::vector<std::string> c;
  for (const auto& t : terms()) c.emplace_back(t.column);
  for (const char* s : {"energy_error [J]", "interfaces_damaged", "interfaces_failed"}) c.emplace_back(s);
  return c;
}

void append_energy_row(const Energies& e, std::vector<double>& row) {
  for (size_t i = 0; i < terms().size(); ++i) row.push_back(term_value(e, i));
  row.push_back(e.balance_error);
  row.push_back(static_cast<double>(e.damaged));
  row.push_back(static_cast<double>(e.failed));
}

}  // namespace fdem
