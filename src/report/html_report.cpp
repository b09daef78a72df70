#include "physgrad/report/html_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <tuple>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/report/svg_document.hpp"
#include "physgrad/text.hpp"

namespace physgrad {

namespace {

constexpr const char* kStyle = R"(body{font-family:system-ui,sans-serif;color:#222;line-height:1.45;
  max-width:1280px;margin:1.5em auto;padding:0 .8em}
h1{font-size:1.5em}
h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ddd;padding-bottom:.2em}
p{max-width:60em;overflow-wrap:anywhere}
table{border-collapse:collapse;font-size:.9em}
p.caption{font-weight:600;margin:1.2em 0 .3em}
.table{overflow-x:auto;max-width:100%;margin:0 0 1em}
p.links a{margin-right:1em}
th,td{border:1px solid #ccc;padding:.3em .7em;text-align:right;overflow-wrap:break-word}
th{background:#f3f3f3}
th:first-child,td:first-child{text-align:left}
.figures{display:flex;flex-wrap:wrap;gap:1.5em;align-items:flex-start}
figure{margin:0;min-width:0;max-width:100%}
.figure-scroll>div>svg{display:block;max-width:100%;height:auto}
.figure-scroll{overflow-x:auto;max-width:100%}
figcaption{font-size:.9em;color:#555;margin-top:.3em;max-width:640px}
p.message{font-size:1.15em;font-weight:600;color:#222;margin:.2em 0 .4em}
#pg-compare svg{display:block;width:100%;max-width:900px;height:auto;user-select:none}
.pg-controls label,.pg-controls button{margin-right:1em}
.pg-entry{display:inline-block;border-left:4px solid;padding:0 .4em;margin:.2em .6em .2em 0;cursor:pointer}
.pg-off{opacity:.4;text-decoration:line-through}
.pg-readout{min-height:1.4em;font-size:.9em;overflow-wrap:anywhere}
.pg-picker fieldset label{display:inline-block;margin-right:1em}
.swatch{display:inline-block;width:.8em;height:.8em;margin-right:.4em;vertical-align:-.05em}
@media (max-width:700px){.table table,.table tbody,.table tr,.table td{display:block}
  .table thead{display:none}.table tr{border-top:2px solid #bbb;padding:.2em 0}
  .table td{border:0;text-align:left;white-space:normal;overflow-wrap:anywhere;padding:.1em .3em}
  .table td::before{content:attr(data-h) ": ";color:#555}}
)";

// What of a page's width its figures cannot take (px): the body's padding (2 × 0.8 em) and a
// scroll bar.
constexpr int kPageMargins = 42;

// The width (px) at which an SVG document of svg::open() shows its smallest text at 11 px: its
// width × 11 / its smallest font-size (12 when it names none).
int readable_width(const std::string& svg) {
  constexpr double kSmallestReadable = 11;
  const auto number_after = [&](const std::string& key, std::size_t from) {
    const std::size_t at = svg.find(key, from);
    return at == std::string::npos ? std::pair(0.0, at)
                                   : std::pair(std::atof(svg.c_str() + at + key.size()), at);
  };
  const double width = number_after(" width=\"", 0).first;
  double smallest = 12;
  for (auto [size, at] = number_after("font-size=\"", 0); at != std::string::npos;
       std::tie(size, at) = number_after("font-size=\"", at + 1)) {
    if (size > 0) smallest = std::min(smallest, size);
  }
  return static_cast<int>(std::ceil(width * kSmallestReadable / smallest));
}

// The narrow layout of a responsive figure (svg::responsive), else the figure itself.
std::string narrow_layout(const std::string& svg) {
  try {
    return svg::layouts(svg).narrow;
  } catch (const Error&) {
    return svg;  // not a document of svg::open(): shown as it is
  }
}

bool blank(std::string_view line) {
  return line.find_first_not_of(" \t\r") == std::string_view::npos;
}

bool is_hex_colour(const std::string& text) {
  return text.size() == 7 && text[0] == '#' &&
         std::all_of(text.begin() + 1, text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
         });
}

// Throws Error when the table's links or colours do not have a row per row.
void check_table_shape(const HtmlTable& table, const std::string& where) {
  for (const auto& [cells, what] : {std::pair(&table.links, "links"),
                                     std::pair(&table.colours, "colours")}) {
    if (!cells->empty() && cells->size() != table.rows.size()) {
      throw Error("html_report: a table in " + where + " has " +
                  std::to_string(table.rows.size()) + " rows but " +
                  std::to_string(cells->size()) + " rows of " + what);
    }
  }
}

}  // namespace

std::string local_href(std::string_view relative_path) {
  static const char* const digits = "0123456789ABCDEF";
  std::string out = ".";
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = relative_path.find('/', start);
    const std::string_view segment = relative_path.substr(start, end - start);
    if (segment.empty() || segment == "." || segment == "..") {
      throw Error("html_report: cannot link to '" + shown_text(relative_path) +
                  "': a segment is empty, '.' or '..'");
    }
    out += '/';
    for (const char c : segment) {
      const auto byte = static_cast<unsigned char>(c);
      if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' ||
          c == '.' || c == '_' || c == '~') {
        out += c;
      } else {
        out += '%';
        out += digits[byte >> 4];
        out += digits[byte & 0xF];
      }
    }
    if (end == std::string_view::npos) return out;
    start = end + 1;
  }
}

std::string html_paragraphs(std::string_view text) {
  std::string out, paragraph;
  const auto flush = [&] {
    if (!paragraph.empty()) out += "<p>" + xml_escape(paragraph) + "</p>\n";
    paragraph.clear();
  };
  while (!text.empty()) {
    const std::size_t end = text.find('\n');
    const std::string_view line = text.substr(0, end);
    text = end == std::string_view::npos ? std::string_view{} : text.substr(end + 1);
    if (blank(line)) {
      flush();
    } else {
      if (!paragraph.empty()) paragraph += '\n';
      paragraph += line;
    }
  }
  flush();
  return out;
}

std::string html_table_open(const HtmlTable& table) {
  // The caption sits above the scroll box, as wide as the text, however narrow the table.
  std::string out;
  if (!table.caption.empty()) {
    out += "<p class=\"caption\">" + xml_escape(table.caption) + "</p>\n";
  }
  out += "<div class=\"table\"><table>\n<thead><tr>";
  for (const std::string& h : table.header) out += "<th>" + xml_escape(h) + "</th>";
  return out + "</tr></thead>\n<tbody>\n";
}

std::string html_table_rows(const HtmlTable& table, const std::string& where) {
  check_table_shape(table, where);
  const auto check = [&](std::size_t cells, std::size_t r, const char* what) {
    if (cells != table.header.size()) {
      throw Error("html_report: " + std::string(what) + " " + std::to_string(r + 1) +
                  " of a table in " + where + " has " + std::to_string(cells) +
                  " cells but the header has " + std::to_string(table.header.size()));
    }
  };
  std::string out;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const auto& row = table.rows[r];
    check(row.size(), r, "row");
    if (!table.links.empty()) check(table.links[r].size(), r, "row of links");
    if (!table.colours.empty()) check(table.colours[r].size(), r, "row of colours");
    out += "<tr>";
    for (std::size_t c = 0; c < row.size(); ++c) {
      const std::string link = table.links.empty() ? std::string() : table.links[r][c];
      const std::string colour = table.colours.empty() ? std::string() : table.colours[r][c];
      out += "<td data-h=\"" + xml_escape(table.header[c]) + "\">";
      if (!colour.empty()) {
        if (!is_hex_colour(colour)) {
          throw Error("html_report: '" + shown_text(colour) + "' in a table in " + where +
                      " is not a colour #rrggbb");
        }
        out += "<span class=\"swatch\" style=\"background:" + colour + "\"></span>";
      }
      out += link.empty()
                 ? xml_escape(row[c])
                 : "<a href=\"" + local_href(link) + "\">" + xml_escape(row[c]) + "</a>";
      out += "</td>";
    }
    out += "</tr>\n";
  }
  return out;
}

std::string html_table(const HtmlTable& table, const std::string& where) {
  std::string rows = html_table_rows(table, where);  // checked before anything is written
  return html_table_open(table) + rows + std::string(kHtmlTableClose);
}

std::string html_page_open(const std::string& title, const std::string& intro,
                           const std::string& csp) {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n" +
         (csp.empty() ? std::string()
                      : "<meta http-equiv=\"Content-Security-Policy\" content=\"" +
                            xml_escape(csp) + "\">\n") +
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
         "<title>" +
         xml_escape(title) + "</title>\n<style>\n" + kStyle + "</style>\n</head>\n<body>\n" +
         "<h1>" + xml_escape(title) + "</h1>\n" + html_paragraphs(intro);
}

std::string html_anchor_id(std::string_view text) {
  std::string out = "s-";
  for (const char c : text) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
    out += keep ? c : (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : '-';
  }
  return out;
}

std::string html_contents(const std::vector<std::pair<std::string, std::string>>& entries) {
  std::string out = "<nav class=\"contents\"><p class=\"links\">Contents:";
  for (const auto& [text, id] : entries) {
    out += " <a href=\"#" + html_anchor_id(id) + "\">" + xml_escape(text) + "</a>";
  }
  return out + "</p></nav>\n";
}

std::string html_section_open(const HtmlSection& section) {
  std::string out = section.id.empty()
                        ? std::string("<section>\n")
                        : "<section id=\"" + html_anchor_id(section.id) + "\">\n";
  if (!section.heading.empty()) out += "<h2>" + xml_escape(section.heading) + "</h2>\n";
  if (!section.links.empty()) {
    out += "<p class=\"links\">";
    for (const HtmlLink& link : section.links) {
      const std::string href = local_href(link.path);
      out += "<a href=\"" + (link.up ? "." + href : href) + "\">" + xml_escape(link.text) +
             "</a>";
    }
    out += "</p>\n";
  }
  return out + html_paragraphs(section.text);
}

std::string html_figures(const std::vector<HtmlFigure>& figures) {
  std::string out;
  for (std::size_t k = 0; k < figures.size(); ++k) {
    const HtmlFigure& figure = figures[k];
    if (k == 0 || figure.row != figures[k - 1].row) {
      out += std::string(k == 0 ? "" : "</div>\n") + "<div class=\"figures\">\n";
    }
    // The wide layout scales with the page down to the width at which its smallest text is
    // 11 px; in a page narrower than that (its margins and a scroll bar aside) the narrow one.
    const std::string narrow = narrow_layout(figure.svg);
    const std::string svg =
        figure.svg == narrow
            ? figure.svg
            : svg::switched_below(figure.svg, readable_width(svg::layouts(figure.svg).wide) +
                                                  kPageMargins);
    // The message sentence above the figure, so that it is read first (and on the first screen).
    out += (figure.id.empty() ? std::string("<figure>\n")
                              : "<figure id=\"" + xml_escape(figure.id) + "\">\n") +
           (figure.message.empty()
                ? std::string()
                : "<p class=\"message\">" + xml_escape(figure.message) + "</p>\n") +
           "<div class=\"figure-scroll\"><div style=\"min-width:" +
           std::to_string(readable_width(narrow)) + "px\">\n" + svg + "</div></div>\n";
    if (!figure.caption.empty()) {
      out += "<figcaption>" + xml_escape(figure.caption) + "</figcaption>\n";
    }
    out += "</figure>\n";
  }
  if (!figures.empty()) out += "</div>\n";
  return out;
}

std::string html_report(const std::string& title, const std::string& intro,
                        const std::vector<HtmlSection>& sections, const std::string& extra,
                        const std::string& csp) {
  std::string out = html_page_open(title, intro, csp);
  for (const HtmlSection& section : sections) {
    out += html_section_open(section);
    for (const HtmlTable& table : section.tables) {
      out += html_table(table, "section '" + section.heading + "'");
    }
    out += html_figures(section.figures);
    out += kHtmlSectionClose;
  }
  return out + extra + std::string(kHtmlPageClose);
}

}  // namespace physgrad
