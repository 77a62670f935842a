#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <sstream>
#include <string>

namespace qswarm {

// A number flag's check: a finite value in [lo, hi]. CLI11's own Range lets NaN through (every
// comparison with NaN is false), and `--time-scale nan` then ran an unpaced run; this refuses it,
// naming the flag (CLI11 prefixes the option's name) and exit 2 follows from the parse error.
inline CLI::Validator finite_range(double lo, double hi) {
  std::ostringstream desc;
  desc << "FINITE in [" << lo << ", " << hi << "]";
  return CLI::Validator(
      [lo, hi, d = desc.str()](std::string& text) -> std::string {
        double v = 0.0;
        std::size_t used = 0;
        try {
          v = std::stod(text, &used);
        } catch (const std::exception&) {
          return "expected a number, got '" + text + "'";
        }
        if (used != text.size()) return "expected a number, got '" + text + "'";
        if (!std::isfinite(v) || v < lo || v > hi) return "expected " + d + ", got " + text;
        return "";
      },
      desc.str());
}

}  // namespace qswarm
