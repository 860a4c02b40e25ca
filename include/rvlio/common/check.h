#pragma once
// Programmer-error checks: abort with file and line. Bad *data* is never
// checked with these; it is returned as a Status (common/status.h).
#include <cstdio>
#include <cstdlib>

#define RVLIO_CHECK(cond)                                                        \
  do {                                                                           \
    if (!(cond)) {                                                               \
      std::fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                              \
    }                                                                            \
  } while (0)

#define RVLIO_CHECK_MSG(cond, msg)                                                       \
  do {                                                                                   \
    if (!(cond)) {                                                                       \
      std::fprintf(stderr, "%s:%d: check failed: %s (%s)\n", __FILE__, __LINE__, #cond, msg); \
      std::abort();                                                                      \
    }                                                                                    \
  } while (0)
