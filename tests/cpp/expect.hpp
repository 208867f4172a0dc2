// The check harness of the C++ tests that print their failures: EXPECT(cond, what) counts a
// check and prints the first 20 failed ones with file and line; main() reports the counts.
#pragma once

#include <cstdio>
#include <string>

namespace test_support {

inline int g_failures = 0, g_checks = 0;

inline void expect(bool ok, const std::string& what, const char* file, int line) {
  ++g_checks;
  if (ok) return;
  if (++g_failures <= 20) std::printf("FAIL %s:%d: %s\n", file, line, what.c_str());
}

}  // namespace test_support

#define EXPECT(cond, what) test_support::expect((cond), (what), __FILE__, __LINE__)
