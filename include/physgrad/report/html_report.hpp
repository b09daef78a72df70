// html_report — one self-contained HTML5 page of sections with text, links, captioned tables and
// inline SVG figures; no external resources and no script of its own (a page may add the
// interactive comparison of compare_view.hpp under its policy). Readable down to phone widths: a
// figure scales with the page down to the width w·11/s at which its smallest text (s px) is
// 11 px, and one with a narrow layout (svg::responsive) switches to it below that; tables become
// one block per row ("header: value" lines) below 700 px, and what is still wider scrolls in
// its own box. Every text goes through xml_escape and every link through local_href.
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
  // link to that file: a path relative to the page's folder, segments separated by '/'.
  std::vector<std::vector<std::string>> links{};
  // Optional colours, shaped as links: a cell's "#rrggbb" draws a square of that colour before
  // its text (e.g. a rule's colour, as its figures draw it).
  std::vector<std::vector<std::string>> colours{};
};

struct HtmlFigure {
  std::string caption;
  std::string svg;  // an SVG document, embedded as is
  std::string id{};  // the figure element's id (an anchor), e.g. its file name; empty: none
  std::string message{};  // the point the figure makes, in one sentence, shown above the figure
  // Consecutive figures of one row key share a row (e.g. one setting's landscape beside its loss
  // plot), wrapping only when the page is too narrow; a new key starts a new row.
  std::string row{};
};

// A link in a section's line of links: to a file inside the page's folder (a path as for
// HtmlTable::links), or with `up`, to one in the folder above it (e.g. the index of the run
// folders, "../index.html").
struct HtmlLink {
  std::string text, path;
  bool up = false;
};

struct HtmlSection {
  std::string heading;
  std::string text;  // plain text; blank lines separate paragraphs
  std::vector<HtmlTable> tables;
  std::vector<HtmlFigure> figures;
  std::vector<HtmlLink> links{};  // one line of links under the heading
  std::string id{};  // the section's anchor (html_anchor_id of it); empty: none
};

// A text as an element id: lower-case letters, digits and '-' (every other character '-'),
// prefixed by "s-"; "Every run" → "s-every-run".
std::string html_anchor_id(std::string_view text);

// A table of contents: one line of links to the sections' anchors, (text, id) each.
std::string html_contents(const std::vector<std::pair<std::string, std::string>>& entries);

// The address of a file inside the page's folder, for href and src: "./" and the path's
// '/'-separated segments, each percent-encoded but for RFC 3986's unreserved characters
// (A–Z a–z 0–9 - . _ ~), so that no name reads as a scheme ("javascript:"), a host, a query, a
// fragment or an escape. "a#b/report.html" → "./a%23b/report.html". Throws Error on an empty,
// "." or ".." segment (an absolute path, or one that leaves the folder).
std::string local_href(std::string_view relative_path);

// Throws Error when a table row's cell count (or a row of its links or colours) differs from its
// header's, a link is not a path local_href takes, or a colour is not "#rrggbb".
// `extra`: HTML written after the sections (e.g. compare_section_open … close), under the page's
// policy `csp` (html_page_open).
std::string html_report(const std::string& title, const std::string& intro,
                        const std::vector<HtmlSection>& sections, const std::string& extra = "",
                        const std::string& csp = "");

// The page in parts, in the order they are written, for a page too large to hold at once
// (html_report() is their concatenation): the page's start (head, title, intro); per section its
// opening (heading, links, text), its tables — each whole (html_table), or as its opening
// (caption and header), its rows written in turns and kHtmlTableClose — its figures and
// kHtmlSectionClose; then kHtmlPageClose. `where` names the table in errors ("section 'Runs'").
// A non-empty `csp` is the page's Content-Security-Policy (a meta element), e.g. compare_csp().
std::string html_page_open(const std::string& title, const std::string& intro,
                           const std::string& csp = "");
// Plain text as paragraphs (<p>), blank lines separating them.
std::string html_paragraphs(std::string_view text);
std::string html_section_open(const HtmlSection& section);
std::string html_table(const HtmlTable& table, const std::string& where);
std::string html_table_open(const HtmlTable& table);
std::string html_table_rows(const HtmlTable& table, const std::string& where);
inline constexpr std::string_view kHtmlTableClose = "</tbody>\n</table></div>\n";
// The figures in rows (HtmlFigure::row); a responsive figure carries the rule that switches it to
// its narrow layout where the page is narrower than the wide one (its margins included).
std::string html_figures(const std::vector<HtmlFigure>& figures);
inline constexpr std::string_view kHtmlSectionClose = "</section>\n";
inline constexpr std::string_view kHtmlPageClose = "</body>\n</html>\n";

}  // namespace physgrad
