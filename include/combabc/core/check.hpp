#pragma once
// COMBABC_CHECK guards invariants that only a bug can break; it is active in every build type
// because a wrong posterior is worse than a crash.
#include <cstdio>
#include <cstdlib>

#define COMBABC_CHECK(expr)                                                                  \
  do {                                                                                       \
    if (!(expr)) {                                                                           \
      std::fprintf(stderr, "%s:%d: internal check failed: %s\n", __FILE__, __LINE__, #expr); \
      std::abort();                                                                          \
    }                                                                                        \
  } while (false)
