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
  std::size_t rows_left_out = 0;               // rows beyond CsvSelection::max_rows

  // The index of a column, or columns.size() when there is none of that name.
  std::size_t column(std::string_view name) const;
};

// What parse_csv keeps of a document: the named columns (in the document's order; every column
// when empty) of its first `max_rows` rows. The rows after those are checked and counted only,
// and a header of more than `max_columns` cells is refused, so that the memory taken is bounded
// by what is kept, whatever the text.
struct CsvSelection {
  std::vector<std::string> columns{};
  std::size_t max_rows = std::size_t(-1);
  std::size_t max_columns = 4096;
};

// Reads a CSV document (RFC 4180 quoting; "\n" or "\r\n" line ends; a final line end optional).
// Throws Error naming the line of a row whose cell count differs from the header's, or of an
// unterminated quote, and naming the count of a header of more than max_columns cells.
CsvData parse_csv(std::string_view text, const CsvSelection& selection = {});

}  // namespace physgrad
