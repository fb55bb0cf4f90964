// Shared by the C++ harnesses: a failed-check counter and printf-style
// formatting, so a harness prints every check and fails at the end.
#pragma once

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

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

// How many times more random roots match the stamped value of a "lower is
// better" measure, interpolated between measured (multiple, value) pairs in
// increasing multiple; "<= 1x" or "> Nx" outside the measured range.
inline std::string matching_multiple(double stamped, const std::vector<std::pair<double, double>>& random) {
  if (random.empty() || stamped >= random.front().second) return "<= 1x";
  for (size_t k = 0; k + 1 < random.size(); ++k) {
    const auto [ma, a] = random[k];
    const auto [mb, b] = random[k + 1];
    if (stamped <= a && stamped >= b) return fmt("~%.1fx", ma + (a - stamped) / std::max(a - b, 1e-12) * (mb - ma));
  }
  return fmt("> %.0fx", random.back().first);
}

}  // namespace check
