// html_report — one self-contained HTML5 page of sections with text, captioned tables and inline
// SVG figures; no external resources. Readable down to phone widths: wide tables scroll in their
// own box and figures scale to the page.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace physgrad {

struct HtmlTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;  // each with header.size() cells
  std::string caption{};                       // above the table: what it shows, its units
  // Optional links: empty, or one row per row of `rows` whose non-empty cells make the cell a
  // link to that address.
  std::vector<std::vector<std::string>> links{};
};

struct HtmlFigure {
  std::string caption;
  std::string svg;  // an SVG document, embedded as is
  std::string id{};  // the figure element's id (an anchor), e.g. its file name; empty: none
};

struct HtmlSection {
  std::string heading;
  std::string text;  // plain text; blank lines separate paragraphs
  std::vector<HtmlTable> tables;
  std::vector<HtmlFigure> figures;
};

// Escapes & < > " ' for use in HTML (and XML) text and attribute values.
std::string html_escape(std::string_view text);

// Throws Error when a table row's cell count (or a row of its links) differs from its header's.
std::string html_report(const std::string& title, const std::string& intro,
                        const std::vector<HtmlSection>& sections);

}  // namespace physgrad
