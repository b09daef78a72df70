#include "physgrad/io/csv.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <utility>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

std::string csv_number(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::array<char, 32> buf{};
  const auto end = std::to_chars(buf.data(), buf.data() + buf.size(), v).ptr;
  return {buf.data(), end};
}

std::string csv_quote(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + '"';
}

struct CellText {
  std::string operator()(double v) const { return csv_number(v); }
  std::string operator()(long long v) const { return std::to_string(v); }
  std::string operator()(const std::string& s) const { return csv_quote(s); }
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
  for (const std::string& c : columns_) fields.push_back(csv_quote(c));
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

namespace {

// The reader of parse_csv(): cells and records as the characters end them, the header's columns
// kept per the selection, the rows kept up to its limit.
class CsvReader {
 public:
  explicit CsvReader(const CsvSelection& selection) : selection_(selection) {}

  // Reads the whole text; a quote never closed is an Error naming the line it opened on (or
  // before).
  CsvData read(std::string_view text) && {
    bool quoted = false, any = false;
    for (std::size_t k = 0; k < text.size(); ++k) {
      const char c = text[k];
      any = true;
      if (quoted) {
        if (c == '"' && k + 1 < text.size() && text[k + 1] == '"') {
          cell_ += '"';
          ++k;
        } else if (c == '"') {
          quoted = false;
        } else {
          if (c == '\n') ++line_;
          cell_ += c;
        }
      } else if (c == '"') {
        quoted = true;
      } else if (c == ',') {
        end_cell();
      } else if (c == '\n' || c == '\r') {
        if (c == '\r' && k + 1 < text.size() && text[k + 1] == '\n') ++k;
        end_record();
        any = false;
        ++line_;
      } else {
        cell_ += c;
      }
    }
    if (quoted) {
      throw Error("csv: a quote opened on or before line " + std::to_string(line_) +
                  " is never closed");
    }
    if (any) end_record();
    return std::move(data_);
  }

 private:
  static constexpr std::size_t kNotKept = std::size_t(-1);

  void end_cell() {
    if (in_header_) {
      if (cells_ < selection_.max_columns) header_.push_back(std::move(cell_));
    } else if (cells_ < slot_.size() && slot_[cells_] != kNotKept &&
               data_.rows.size() < selection_.max_rows) {
      row_[slot_[cells_]] = std::move(cell_);
    }
    cell_.clear();
    ++cells_;
  }

  // The header's columns: those selected (all when none is) are kept, in the header's order.
  void end_header() {
    if (cells_ > selection_.max_columns) {
      throw Error("csv: the header has " + std::to_string(cells_) + " cells, more than the " +
                  std::to_string(selection_.max_columns) + " read");
    }
    const auto& wanted = selection_.columns;
    for (std::string& name : header_) {
      const bool kept =
          wanted.empty() || std::find(wanted.begin(), wanted.end(), name) != wanted.end();
      slot_.push_back(kept ? data_.columns.size() : kNotKept);
      if (kept) data_.columns.push_back(std::move(name));
    }
    in_header_ = false;
  }

  void end_record() {
    end_cell();
    if (in_header_) {
      end_header();
    } else if (cells_ != slot_.size()) {
      throw Error("csv: row " + std::to_string(record_) + " has " + std::to_string(cells_) +
                  " cells but the header has " + std::to_string(slot_.size()));
    } else if (data_.rows.size() < selection_.max_rows) {
      data_.rows.push_back(std::move(row_));
    } else {
      ++data_.rows_left_out;
    }
    row_.assign(data_.columns.size(), std::string());
    cells_ = 0;
    ++record_;
  }

  const CsvSelection& selection_;
  CsvData data_;
  std::vector<std::string> header_, row_;
  std::vector<std::size_t> slot_;  // per column of the header: its place in a kept row
  std::string cell_;
  std::size_t cells_ = 0;   // cells of the current record so far
  std::size_t record_ = 1;  // the header is record 1
  std::size_t line_ = 1;
  bool in_header_ = true;
};

}  // namespace

CsvData parse_csv(std::string_view text, const CsvSelection& selection) {
  return CsvReader(selection).read(text);
}

}  // namespace physgrad
