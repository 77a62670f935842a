// What a test expects a call to refuse: the message of the exception of type E it throws.
#pragma once

#include <stdexcept>
#include <string>

namespace qswarm {

// The message of the E that f() throws, or "" if it throws none (another exception escapes).
template <typename E = std::invalid_argument, typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

}  // namespace qswarm
