#pragma once

#include <string>
#include <vector>

namespace qswarm {

// A comma-separated list as people write it on a command line (--peer-hosts, a list of Discovery
// Servers): "a,b,,c" -> {"a", "b", "", "c"}; "" -> {}. Empty entries are kept, for the caller to
// refuse by name.
std::vector<std::string> split_names(const std::string& text);

}  // namespace qswarm
