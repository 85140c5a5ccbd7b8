// history.csv: a header of column names, then one row per output interval, each written whole.
#include <fcntl.h>
#include <unistd.h>

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

// The error of writing all of `text` to `fd` (0 when it was written).
int write_all(int fd, const std::string& text) {
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return errno;
    if (n == 0) return EIO;
    done += static_cast<size_t>(n);
  }
  return 0;
}

}  // namespace

HistoryWriter::HistoryWriter(const std::string& path, const std::vector<std::string>& columns)
    : path_(path), columns_(columns) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    const int err = errno;
    throw InputError("cannot open history file '" + path + "' for writing: " + std::strerror(err));
  }
  try {
    append(header_line(columns_));
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
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
  fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd_ < 0) {
    const int err = errno;
    throw InputError("cannot open history file '" + path + "' for appending: " +
                     std::strerror(err));
  }
  complete_ = static_cast<long long>(text.size());
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
  if (fd_ >= 0) ::close(fd_);
}

void HistoryWriter::append(const std::string& text) {
  const int err = write_all(fd_, text);
  if (err == 0) {
    complete_ += static_cast<long long>(text.size());
    return;
  }
  // Part of the line may be in the file: cut it back to the last complete line (not possible on
  // a device such as /dev/full, which holds nothing anyway).
  std::string after;
  if (::ftruncate(fd_, static_cast<off_t>(complete_)) == 0)
    after = "; the file is cut back to its last complete row";
  throw InputError("cannot write history file '" + path_ + "': " + std::strerror(err) + after);
}

void HistoryWriter::row(const std::vector<double>& values) {
  if (values.size() != columns_.size()) {
    throw std::logic_error("HistoryWriter::row: " + std::to_string(values.size()) +
                           " values for " + std::to_string(columns_.size()) + " columns in '" +
                           path_ + "'");
  }
  append(format_row(values));
}

}  // namespace fdem
