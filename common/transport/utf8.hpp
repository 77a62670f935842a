#pragma once

#include <string>
#include <string_view>

namespace qswarm {

// Whether `s` is well-formed UTF-8 (no overlong forms, no surrogates, nothing past U+10FFFF).
bool valid_utf8(std::string_view s);

// `s` with every byte that is not part of a well-formed UTF-8 sequence replaced by U+FFFD: text
// that reaches a viewer (a WebSocket text frame must be UTF-8, or the client drops the session),
// whatever a person or the network put in it.
std::string to_valid_utf8(std::string_view s);

}  // namespace qswarm
