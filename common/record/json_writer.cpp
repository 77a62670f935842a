#include "common/record/json_writer.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "common/transport/utf8.hpp"

namespace qswarm {

JsonWriter& JsonWriter::key(std::string_view k) {
  str(k);
  out_ += ':';
  return *this;
}

JsonWriter& JsonWriter::str(std::string_view text) {
  // Valid UTF-8 whatever it was given: a text frame that is not ends a client's session.
  const std::string valid = valid_utf8(text) ? std::string() : to_valid_utf8(text);
  const std::string_view s = valid.empty() ? text : std::string_view(valid);
  out_ += '"';
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out_ += '\\';
      out_ += c;
    } else if (u < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", u);
      out_ += buf;
    } else {
      out_ += c;
    }
  }
  out_ += '"';
  return *this;
}

JsonWriter& JsonWriter::num(double v, int decimals) {
  if (!std::isfinite(v)) return raw("null");
  char buf[48];
  int n = std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  if (n < 0 || n >= static_cast<int>(sizeof buf)) return sig(v);  // beyond 1e40: exponent form
  // Trailing zeros carry nothing: "1.5000" -> "1.5", "2.0000" -> "2".
  if (n > 0 && decimals > 0) {
    while (n > 1 && buf[n - 1] == '0') --n;
    if (buf[n - 1] == '.') --n;
    if (n == 2 && buf[0] == '-' && buf[1] == '0') {
      buf[0] = '0';
      n = 1;
    }
  }
  out_.append(buf, static_cast<std::size_t>(n));
  return *this;
}

JsonWriter& JsonWriter::sig(double v) {
  if (!std::isfinite(v)) return raw("null");
  char buf[32];
  const int n = std::snprintf(buf, sizeof buf, "%.6g", v);
  out_.append(buf, static_cast<std::size_t>(n));
  return *this;
}

JsonWriter& JsonWriter::integer(std::int64_t v) {
  out_ += std::to_string(v);
  return *this;
}

}  // namespace qswarm
