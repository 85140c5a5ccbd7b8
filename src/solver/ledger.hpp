#pragma once
// The energy ledger: one table of its terms (name, history column, side of the balance, whether
// it is summed over the processes, where it is accumulated), from which everything that lists the
// energies is generated: the balance, the sum over the processes, the checkpoint vector, the
// history columns and row, and summary.json's "energy" block. Adding a term is one line in
// kBuiltinTerms (with its field in Energies and the code that fills it where the table says), or,
// for a term a module or a test computes on the host, one call to add_energy_term: either way
// every output takes it (tests/test_ledger.cpp adds a dummy term and finds it in each).
#include <functional>
#include <string>
#include <vector>

namespace fdem {

// Energies and balance at one instant (J). balance_error = (E_now - E_initial) - W_ext, with
// E_now the stored and dissipated terms and W_ext the work terms of the ledger.
struct Energies {
  double time = 0;           // the instant they describe (start of the sampled step)
  long step = 0;
  double kinetic = 0, strain = 0, interface_elastic = 0, contact_elastic = 0;
  double fracture = 0, damping = 0, friction = 0;
  double work_external = 0;  // platens + velocity BCs + gravity + point loads
  double balance_error = 0;
  double scale = 0;          // magnitude the error is judged against
  long damaged = 0, failed = 0;
  double momentum[3] = {0, 0, 0};  // total linear momentum sum m v at `time` (N s)
  std::vector<double> added;       // the values of the terms added with add_energy_term, in order
};

enum class EnergySide { stored, dissipated, work };

// A built-in term's member of Energies. An alias, not a spelled-out `double Energies::*field`:
// nvcc's front end writes that as `double (Energies::*field)`, on which g++ 12 warns (-Wparentheses).
using EnergyField = double Energies::*;

struct EnergyTerm {
  const char* key;     // summary.json's "energy" key (with "_J") and the checkpoint's order
  const char* column;  // history.csv
  EnergySide side;
  bool summed;         // each process holds its own share: summed over the processes
  const char* where;   // where it is accumulated (for the reader; docs/developing.md)
  EnergyField field = nullptr;  // a built-in term's value; null: an added one
  // an added term: its value at a sampled instant (time, step), the same on every process
  std::function<double(double, long)> sample = {};
};

// The terms, built-in ones first, in the order of every output. Built-in:
//   kinetic, strain, interface_elastic, contact_elastic (stored), fracture, damping, friction
//   (dissipated), work_external (work).
const std::vector<EnergyTerm>& energy_terms();
// Adds a term computed on the host at each sampled instant (sides as for the built-in ones; not
// summed over processes: the same value on each). For the runs started after the call (its
// column, summary key and checkpoint entry come with it). Returns its index among the added terms.
int add_energy_term(const std::string& key, const std::string& column, EnergySide side,
                    std::function<double(double, long)> sample);
// Removes the added terms (tests).
void clear_added_energy_terms();

// A term's value in e.
double term_value(const Energies& e, size_t term);

// The stored + dissipated energy of e (the built-in order: the same bits as the sum written out).
double energy_now(const Energies& e);
// The work terms' sum.
double energy_work(const Energies& e);
// The added terms sampled at e's time and step (into e.added).
void sample_added_terms(Energies& e);
// Every summed term, the momentum and the damaged / failed counts summed over the processes:
// `sum` is the decomposition's in-place sum (nothing on one process).
void sum_energies(Energies& e, const std::function<void(double*, int)>& sum);

// Energies as a flat array (checkpoints): time, step, the terms in table order up to the last
// built-in one, balance_error, scale, damaged, failed (kEnergyFieldCount values: the layout of the
// checkpoints before the table), then the momentum (3) and the added terms. A shorter, older vector
// (kEnergyFieldCount values) leaves the momentum at zero and the added terms unset.
constexpr int kEnergyFieldCount = 14;
std::vector<double> energies_to_vector(const Energies& e);
// Throws InputError naming `what` when v is shorter than kEnergyFieldCount.
Energies energies_from_vector(const std::vector<double>& v, const std::string& what = "energies");

// History columns of the ledger: one per term, then energy_error, interfaces_damaged and
// interfaces_failed; and the row values in the same order.
std::vector<std::string> energy_columns();
void append_energy_row(const Energies& e, std::vector<double>& row);

}  // namespace fdem
