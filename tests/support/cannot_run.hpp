#pragma once
// A test that cannot run here (no root, no container engine, a device or tool missing) says why.
// Outside CI it is skipped; under CI (CI set, as tools/test.sh sets it) it fails, naming what is
// missing: ctest counts a skipped test as passed, and CI must never pass on what it did not run.
// `why` may be a stream expression: QSWARM_CANNOT_RUN("no cgroup under " << root).
#include <gtest/gtest.h>

#include <cstdlib>

#define QSWARM_CANNOT_RUN(why)                                       \
  do {                                                               \
    if (std::getenv("CI")) FAIL() << "cannot run under CI: " << why; \
    GTEST_SKIP() << why;                                             \
  } while (false)
