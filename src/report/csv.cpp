#include "physgrad/report/csv.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <utility>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

std::string format_double(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::array<char, 32> buf{};
  const auto end = std::to_chars(buf.data(), buf.data() + buf.size(), v).ptr;
  return {buf.data(), end};
}

std::string quote(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + '"';
}

struct CellText {
  std::string operator()(double v) const { return format_double(v); }
  std::string operator()(long long v) const { return std::to_string(v); }
  std::string operator()(const std::string& s) const { return quote(s); }
};

void append_line(std::string& out, const std::vector<std::string>& fields) {
  for (std::size_t k = 0; k < fields.size(); ++k) {
    if (k > 0) out += ',';
    out += fields[k];
  }
  out += '\n';
}

}  // namespace

CsvTable::CsvTable(std::vector<std::string> columns) : columns_(std::move(columns)) {
  if (columns_.empty()) throw Error("csv: a table needs at least one column, got 0");
}

void CsvTable::add_row(std::vector<CsvCell> cells) {
  if (cells.size() != columns_.size()) {
    throw Error("csv: row " + std::to_string(rows_.size() + 1) + " has " +
                std::to_string(cells.size()) + " cells but the table has " +
                std::to_string(columns_.size()) + " columns");
  }
  rows_.push_back(std::move(cells));
}

std::string CsvTable::str() const {
  std::string out;
  std::vector<std::string> fields;
  for (const std::string& c : columns_) fields.push_back(quote(c));
  append_line(out, fields);
  for (const auto& row : rows_) {
    fields.clear();
    for (const CsvCell& cell : row) fields.push_back(std::visit(CellText{}, cell));
    append_line(out, fields);
  }
  return out;
}

}  // namespace physgrad
