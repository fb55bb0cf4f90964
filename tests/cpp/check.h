// Shared by the C++ harnesses: a failed-check counter and printf-style
// formatting, so a harness prints every check and fails at the end.
#pragma once

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <stdexcept>
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

// How many times more uniformly random roots give the stamped roots' value of
// a "lower is better" measure, linear between measured (multiple, value)
// pairs in increasing multiple. Outside the measured range nothing is
// extrapolated: `where` says on which side the stamped value lies.
struct Multiple {
  enum Where { below, within, above } where;
  double value;  // within: the interpolated multiple; below/above: the range's end

  std::string text() const {
    if (where == below) return fmt("< %.2fx", value);
    if (where == above) return fmt("> %.2fx", value);
    return fmt("%.2fx", value);
  }
  // `min` must lie within the measured range, or "above" would not prove it.
  bool at_least(double min) const { return where == above || (where == within && value >= min); }
};

// Noisy measures need not fall monotonically with the multiple: the first
// crossing counts.
inline Multiple matching_multiple(double stamped, const std::vector<std::pair<double, double>>& random) {
  if (random.empty()) throw std::invalid_argument("matching_multiple: no random measurements");
  if (stamped > random.front().second) return {Multiple::below, random.front().first};
  for (size_t k = 0; k + 1 < random.size(); ++k) {
    const auto [ma, a] = random[k];
    const auto [mb, b] = random[k + 1];
    if (stamped <= a && stamped >= b) {
      return {Multiple::within, ma + (a - stamped) / std::max(a - b, 1e-12) * (mb - ma)};
    }
  }
  return {Multiple::above, random.back().first};
}

}  // namespace check
