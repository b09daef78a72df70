// CsvTable — builds a CSV document (RFC 4180 quoting, "\n" line ends) from typed cells.
// Doubles are written in the shortest form that parses back to the same value.
#pragma once

#include <cstddef>
#include <string>
#include <variant>
#include <vector>

namespace physgrad {

using CsvCell = std::variant<double, long long, std::string>;

class CsvTable {
 public:
  explicit CsvTable(std::vector<std::string> columns);

  // Throws Error unless there is exactly one cell per column.
  void add_row(std::vector<CsvCell> cells);
  // The header line followed by one line per row; NaN and ±Inf are written nan, inf, -inf.
  std::string str() const;
  std::size_t rows() const { return rows_.size(); }

 private:
  std::vector<std::string> columns_;
  std::vector<std::vector<CsvCell>> rows_;
};

}  // namespace physgrad
