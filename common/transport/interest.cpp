#include "common/transport/interest.hpp"

#include <algorithm>

namespace qswarm {

bool Interest::meets(const Interest& from, const Interest& to) {
  if (from.publish.empty() && to.subscribe.empty()) return true;  // both the whole run
  if (from.publish.empty() || to.subscribe.empty()) return false;
  auto a = from.publish.begin(), b = to.subscribe.begin();
  while (a != from.publish.end() && b != to.subscribe.end()) {
    if (*a == *b) return true;
    if (*a < *b) {
      ++a;
    } else {
      ++b;
    }
  }
  return false;
}

}  // namespace qswarm
