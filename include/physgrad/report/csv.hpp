// CsvTable — builds a CSV document (RFC 4180 quoting, "\n" line ends) from typed cells, and
// parse_csv reads one back. Doubles are written in the shortest form that parses back to the
// same value.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
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

// A CSV document as text cells: the header's columns and one row per line.
struct CsvData {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;  // each with columns.size() cells

  // The index of a column, or columns.size() when there is none of that name.
  std::size_t column(std::string_view name) const;
};

// Reads a CSV document (RFC 4180 quoting; "\n" or "\r\n" line ends; a final line end optional).
// Throws Error naming the line of a row whose cell count differs from the header's, or of an
// unterminated quote.
CsvData parse_csv(std::string_view text);

}  // namespace physgrad
