#include "physgrad/report/html_report.hpp"

#include "physgrad/report/svg_plot.hpp"

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

constexpr const char* kStyle = R"(body{font-family:system-ui,sans-serif;color:#222;line-height:1.45;
  max-width:1280px;margin:2em auto;padding:0 1em}
h1{font-size:1.6em}
h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ddd;padding-bottom:.2em}
table{border-collapse:collapse;margin:1em 0;font-size:.9em}
th,td{border:1px solid #ccc;padding:.3em .7em;text-align:right}
th{background:#f3f3f3}
th:first-child,td:first-child{text-align:left}
.figures{display:flex;flex-wrap:wrap;gap:1.5em;align-items:flex-start}
figure{margin:0}
figure svg{display:block;max-width:100%;height:auto}
figcaption{font-size:.9em;color:#555;margin-top:.3em;max-width:640px}
)";

bool blank(std::string_view line) {
  return line.find_first_not_of(" \t\r") == std::string_view::npos;
}

// Paragraphs separated by blank lines, each as <p>.
std::string paragraphs(std::string_view text) {
  std::string out, paragraph;
  const auto flush = [&] {
    if (!paragraph.empty()) out += "<p>" + html_escape(paragraph) + "</p>\n";
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

std::string table_html(const HtmlTable& table, const std::string& where) {
  std::string out = "<table>\n<thead><tr>";
  for (const std::string& h : table.header) out += "<th>" + html_escape(h) + "</th>";
  out += "</tr></thead>\n<tbody>\n";
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const auto& row = table.rows[r];
    if (row.size() != table.header.size()) {
      throw Error("html_report: row " + std::to_string(r + 1) + " of a table in " + where +
                  " has " + std::to_string(row.size()) + " cells but the header has " +
                  std::to_string(table.header.size()));
    }
    out += "<tr>";
    for (const std::string& cell : row) out += "<td>" + html_escape(cell) + "</td>";
    out += "</tr>\n";
  }
  return out + "</tbody>\n</table>\n";
}

}  // namespace

std::string html_escape(std::string_view text) { return xml_escape(text); }

std::string html_report(const std::string& title, const std::string& intro,
                        const std::vector<HtmlSection>& sections) {
  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  out += "<title>" + html_escape(title) + "</title>\n<style>\n" + kStyle + "</style>\n";
  out += "</head>\n<body>\n<h1>" + html_escape(title) + "</h1>\n" + paragraphs(intro);
  for (const HtmlSection& section : sections) {
    out += "<section>\n";
    if (!section.heading.empty()) out += "<h2>" + html_escape(section.heading) + "</h2>\n";
    out += paragraphs(section.text);
    for (const HtmlTable& table : section.tables) {
      out += table_html(table, "section '" + section.heading + "'");
    }
    if (!section.figures.empty()) {
      out += "<div class=\"figures\">\n";
      for (const HtmlFigure& figure : section.figures) {
        out += "<figure>\n" + figure.svg;
        if (!figure.caption.empty()) {
          out += "<figcaption>" + html_escape(figure.caption) + "</figcaption>\n";
        }
        out += "</figure>\n";
      }
      out += "</div>\n";
    }
    out += "</section>\n";
  }
  return out + "</body>\n</html>\n";
}

}  // namespace physgrad
