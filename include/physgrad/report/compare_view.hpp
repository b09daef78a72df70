// compare_view — the interactive comparison of runs' curves on a page: one inline script (plain
// JS, kCompareScript) over one inline JSON block, allowed by a Content-Security-Policy naming the
// script's SHA-256 (base64, FIPS 180-4), so that nothing else runs and nothing is requested.
#pragma once

#include <string>
#include <string_view>

namespace physgrad {

// The script: reads the element #pg-compare-data ({"runs": [{"g": group, "l": label, "s": seed,
// "c": {column: [values]}}]}, x columns "iteration" and "wall_seconds") and builds its view in
// #pg-compare with DOM calls and textContent only.
extern const std::string_view kCompareScript;

// JSON text made safe inside <script type="application/json">: '<', '>', '&', '=' and
// U+2028/U+2029 written as \u003c, \u003e, \u0026, \u003d, \u2028, \u2029 — for valid JSON only
// (these characters occur in JSON text only inside strings), so that no value can close the
// block, open a comment or read as an attribute.
std::string json_for_script(std::string_view json_text);

// The SHA-256 digest of `text`, base64-encoded (RFC 4648, with padding).
std::string sha256_base64(std::string_view text);

// The page's policy: default-src 'none'; the script by its hash; inline styles; data: images.
std::string compare_csp();

// The component's section, in parts: its opening (heading, what it shows, a <noscript> note, the
// container, the opening of the JSON block), then the caller writes json_for_script text of the
// data, then the close (the JSON block's end, the script, the section's end).
std::string compare_section_open(const std::string& heading, const std::string& text);
std::string compare_section_close();

}  // namespace physgrad
