// history.csv: a header of column names, then one row per output interval, flushed each row.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "io/output.hpp"

namespace fdem {

namespace {

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

// The header line: the column names, comma separated, newline.
std::string header_line(const std::vector<std::string>& columns) {
  std::string header;
  for (size_t i = 0; i < columns.size(); ++i) {
    if (i) header += ',';
    header += csv_field(columns[i]);
  }
  header += '\n';
  return header;
}

}  // namespace

HistoryWriter::HistoryWriter(const std::string& path, const std::vector<std::string>& columns)
    : path_(path), columns_(columns) {
  f_ = std::fopen(path.c_str(), "w");
  if (!f_) {
    const int err = errno;
    throw InputError("cannot open history file '" + path + "' for writing: " + std::strerror(err));
  }
  const std::string header = header_line(columns_);
  if (std::fputs(header.c_str(), f_) < 0 || std::fflush(f_) != 0) {
    const int err = errno;
    std::fclose(f_);
    f_ = nullptr;
    throw InputError("cannot write history file '" + path + "': " + std::strerror(err));
  }
}

HistoryWriter::HistoryWriter(const std::string& path, const std::vector<std::string>& columns,
                             const std::vector<double>& earlier_rows)
    : path_(path), columns_(columns) {
  const size_t nc = columns_.size();
  if (nc == 0 || earlier_rows.size() % nc != 0)
    throw std::logic_error("HistoryWriter: earlier rows do not fit the columns of '" + path + "'");
  std::string text = header_line(columns_);
  std::vector<double> row(nc);
  for (size_t r = 0; r < earlier_rows.size() / nc; ++r) {
    row.assign(earlier_rows.begin() + static_cast<long>(r * nc),
               earlier_rows.begin() + static_cast<long>((r + 1) * nc));
    text += format_row(row);
  }
  write_file_atomic(path, text);
  f_ = std::fopen(path.c_str(), "a");
  if (!f_) {
    const int err = errno;
    throw InputError("cannot open history file '" + path + "' for appending: " +
                     std::strerror(err));
  }
}

std::string HistoryWriter::format_row(const std::vector<double>& values) {
  std::string line;
  char buf[64];
  for (size_t i = 0; i < values.size(); ++i) {
    if (i) line += ',';
    std::snprintf(buf, sizeof buf, "%.10g", values[i]);
    line += buf;
  }
  line += '\n';
  return line;
}

HistoryWriter::~HistoryWriter() {
  if (f_) std::fclose(f_);
}

void HistoryWriter::row(const std::vector<double>& values) {
  if (values.size() != columns_.size()) {
    throw std::logic_error("HistoryWriter::row: " + std::to_string(values.size()) +
                           " values for " + std::to_string(columns_.size()) + " columns in '" +
                           path_ + "'");
  }
  const std::string line = format_row(values);
  if (std::fputs(line.c_str(), f_) < 0 || std::fflush(f_) != 0) {
    const int err = errno;
    throw InputError("cannot write history file '" + path_ + "': " + std::strerror(err));
  }
}

}  // namespace fdem
