#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <CLI/CLI.hpp>

#include <cmath>
#include <set>
#include <sstream>
#include <string>

#include "common/transport/port_plan.hpp"

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

// Why DDS cannot bind to `address` on this machine ("" when it can): "any", or an IPv4 address one
// of the machine's interfaces holds. An address that is not here would leave the participant with
// no interface to send or hear on: the agent would wait out its start timeout and fly alone.
inline std::string interface_problem(const std::string& address) {
  if (address == "any") return "";
  in_addr want{};
  if (inet_pton(AF_INET, address.c_str(), &want) != 1)
    return "expected \"any\" or an IPv4 address such as 127.0.0.1, got \"" + address + "\"";
  const std::set<std::string> here = local_ipv4_addresses();
  if (here.empty()) return "";  // cannot tell: let DDS try
  char canonical[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &want, canonical, sizeof canonical);
  if (here.count(canonical)) return "";
  std::string names;
  for (const std::string& h : here) names += (names.empty() ? "" : ", ") + h;
  return "expected \"any\" or an IPv4 address of this machine (" + names + "), got \"" + address +
         "\"";
}

}  // namespace qswarm
