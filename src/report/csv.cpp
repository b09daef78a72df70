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

std::size_t CsvData::column(std::string_view name) const {
  for (std::size_t k = 0; k < columns.size(); ++k) {
    if (columns[k] == name) return k;
  }
  return columns.size();
}

CsvData parse_csv(std::string_view text) {
  std::vector<std::vector<std::string>> lines;
  std::vector<std::string> cells;
  std::string cell;
  std::size_t line = 1;
  bool quoted = false, any = false;
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    any = true;
    if (quoted) {
      if (c == '"' && k + 1 < text.size() && text[k + 1] == '"') {
        cell += '"';
        ++k;
      } else if (c == '"') {
        quoted = false;
      } else {
        if (c == '\n') ++line;
        cell += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.push_back(std::move(cell));
      cell.clear();
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && k + 1 < text.size() && text[k + 1] == '\n') ++k;
      cells.push_back(std::move(cell));
      cell.clear();
      lines.push_back(std::move(cells));
      cells.clear();
      any = false;
      ++line;
    } else {
      cell += c;
    }
  }
  if (quoted) throw Error("csv: a quote opened on or before line " + std::to_string(line) + " is never closed");
  if (any) {
    cells.push_back(std::move(cell));
    lines.push_back(std::move(cells));
  }
  CsvData data;
  if (lines.empty()) return data;
  data.columns = std::move(lines.front());
  for (std::size_t r = 1; r < lines.size(); ++r) {
    if (lines[r].size() != data.columns.size()) {
      throw Error("csv: row " + std::to_string(r + 1) + " has " + std::to_string(lines[r].size()) +
                  " cells but the header has " + std::to_string(data.columns.size()));
    }
    data.rows.push_back(std::move(lines[r]));
  }
  return data;
}

}  // namespace physgrad
