// Shared by the libFuzzer targets of tests/fuzz: a contract check that turns a broken promise of the engine
// (a result that is neither a value nor an Error with a message, an index out of range, ...) into a crash that
// libFuzzer reports with the input that caused it.
#pragma once

#include <cstdio>
#include <cstdlib>

#define VISBUF_FUZZ_CHECK(cond, what)                                                     \
  do {                                                                                    \
    if (!(cond)) {                                                                        \
      std::fprintf(stderr, "fuzz contract violated: %s (%s:%d)\n", what, __FILE__, __LINE__); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (0)
