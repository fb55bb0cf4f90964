// Shared by the C++ harnesses: a failed-check counter and printf-style
// formatting, so a harness prints every check and fails at the end.
#pragma once

#include <cstdarg>
#include <cstdio>
#include <string>

namespace check {

inline int failures = 0;

inline void expect(bool ok, const std::string& what) {
  std::printf("  %s  %s\n", ok ? "PASS" : "FAIL", what.c_str());
  if (!ok) ++failures;
}

inline std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
inline std::string fmt(const char* f, ...) {
  char buf[512];
  va_list args;
  va_start(args, f);
  std::vsnprintf(buf, sizeof buf, f, args);
  va_end(args);
  return buf;
}

}  // namespace check
