// Numbers shown with the digits their spread supports: a median over seeds with as many
// significant digits as resolve its range to two digits, d = ⌊log₁₀|m|⌋ − ⌊log₁₀(max − min)⌋ + 2
// (1 ≤ d ≤ 6); a single value (one seed) with two; whole numbers as they are.
#pragma once

#include <string>
#include <vector>

namespace physgrad {

// The median, minimum and maximum of the finite values, and how many there are (NaN: none).
struct Spread {
  std::size_t count = 0;
  double median = 0.0 / 0.0, low = 0.0 / 0.0, high = 0.0 / 0.0;
};
Spread spread_of(std::vector<double> values);

// The significant digits the spread supports (2 for fewer than two distinct values).
int digits_for(const Spread& spread);
// `value` with `digits` significant digits ("%#.*g": 0.50, 1.0); a whole number below 10¹⁵ in
// full; "–" for NaN.
std::string with_digits(double value, int digits);
// "0.0123 (0.0118–0.0131)": the median with the digits its spread supports and the range; a
// single value (or all equal) without the range; "–" for none.
std::string median_and_range(const Spread& spread);
// The digits a ratio a / b of two medians supports: d = ⌊−log₁₀ r⌋ + 2 (1 ≤ d ≤ 4) for the wider
// relative spread r = (max − min) / |median| of the two; two when either is a single value.
int ratio_digits(const Spread& a, const Spread& b);
// The ratio a / b of two medians with ratio_digits(a, b) significant digits.
std::string ratio_text(const Spread& a, const Spread& b);

}  // namespace physgrad
