#include "common/sim/liar.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace qswarm {

Vec3 Liar::claim(AgentId to, const Vec3& q0, double t_s) const {
  switch (kind) {
    case Kind::kConstant:
      return value;
    case Kind::kDrift:
      return q0 + value * t_s;
    case Kind::kSplit:
      return to % 2 == 0 ? value : Vec3(-value);
  }
  return value;
}

std::string to_string(Liar::Kind k) {
  switch (k) {
    case Liar::Kind::kConstant:
      return "constant";
    case Liar::Kind::kDrift:
      return "drift";
    case Liar::Kind::kSplit:
      return "split";
  }
  return "?";
}

Liar::Kind parse_liar_kind(const std::string& s) {
  if (s == "constant") return Liar::Kind::kConstant;
  if (s == "drift") return Liar::Kind::kDrift;
  if (s == "split") return Liar::Kind::kSplit;
  throw std::invalid_argument("expected constant, drift or split, got '" + s + "'");
}

namespace {

double parse_number(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v) || std::abs(v) > 1e6)
    throw std::invalid_argument("expected a finite number of at most 1e6, got '" + text + "'");
  return v;
}

}  // namespace

Liar parse_liar(const std::string& text) {
  const std::string form = "ID:KIND[:X,Y,Z]";
  const std::size_t c1 = text.find(':');
  if (c1 == std::string::npos)
    throw std::invalid_argument("expected " + form + ", got '" + text + "'");
  Liar l;
  const std::string id = text.substr(0, c1);
  char* end = nullptr;
  const unsigned long v = std::strtoul(id.c_str(), &end, 10);
  if (id.empty() || id[0] == '-' || end != id.c_str() + id.size() || v == 0 || v > 1000000)
    throw std::invalid_argument("expected an agent id (1 to 1000000) before ':', got '" + id + "'");
  l.id = static_cast<AgentId>(v);
  const std::size_t c2 = text.find(':', c1 + 1);
  l.kind = parse_liar_kind(
      text.substr(c1 + 1, c2 == std::string::npos ? std::string::npos : c2 - c1 - 1));
  l.value = l.kind == Liar::Kind::kDrift ? kDefaultDrift_mps : kDefaultLie;
  if (c2 == std::string::npos) return l;
  const std::string xyz = text.substr(c2 + 1);
  const std::size_t a = xyz.find(','), b = a == std::string::npos ? a : xyz.find(',', a + 1);
  if (b == std::string::npos || xyz.find(',', b + 1) != std::string::npos)
    throw std::invalid_argument("expected X,Y,Z after the kind, got '" + xyz + "'");
  l.value = Vec3(parse_number(xyz.substr(0, a)), parse_number(xyz.substr(a + 1, b - a - 1)),
                 parse_number(xyz.substr(b + 1)));
  return l;
}

}  // namespace qswarm
