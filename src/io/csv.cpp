#include "physgrad/io/csv.hpp"

#include <algorithm>
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

CsvData parse_csv(std::string_view text, const CsvSelection& selection) {
  constexpr std::size_t kNotKept = std::size_t(-1);
  CsvData data;
  std::vector<std::string> header, row;
  std::vector<std::size_t> slot;  // per column of the header: its place in a kept row
  std::string cell;
  std::size_t cells = 0;   // cells of the current record so far
  std::size_t record = 1;  // the header is record 1
  std::size_t line = 1;
  bool in_header = true;
  const auto end_cell = [&] {
    if (in_header) {
      if (cells < selection.max_columns) header.push_back(std::move(cell));
    } else if (cells < slot.size() && slot[cells] != kNotKept &&
               data.rows.size() < selection.max_rows) {
      row[slot[cells]] = std::move(cell);
    }
    cell.clear();
    ++cells;
  };
  const auto end_record = [&] {
    end_cell();
    if (in_header) {
      if (cells > selection.max_columns) {
        throw Error("csv: the header has " + std::to_string(cells) + " cells, more than the " +
                    std::to_string(selection.max_columns) + " read");
      }
      for (std::string& name : header) {
        const bool kept = selection.columns.empty() ||
                          std::find(selection.columns.begin(), selection.columns.end(), name) !=
                              selection.columns.end();
        slot.push_back(kept ? data.columns.size() : kNotKept);
        if (kept) data.columns.push_back(std::move(name));
      }
      in_header = false;
    } else if (cells != slot.size()) {
      throw Error("csv: row " + std::to_string(record) + " has " + std::to_string(cells) +
                  " cells but the header has " + std::to_string(slot.size()));
    } else if (data.rows.size() < selection.max_rows) {
      data.rows.push_back(std::move(row));
    } else {
      ++data.rows_left_out;
    }
    row.assign(data.columns.size(), std::string());
    cells = 0;
    ++record;
  };
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
      end_cell();
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && k + 1 < text.size() && text[k + 1] == '\n') ++k;
      end_record();
      any = false;
      ++line;
    } else {
      cell += c;
    }
  }
  if (quoted) {
    throw Error("csv: a quote opened on or before line " + std::to_string(line) +
                " is never closed");
  }
  if (any) end_record();
  return data;
}

}  // namespace physgrad
