// squeeze::common — numbers in messages and tables.
#pragma once
#include <cstdio>
#include <string>

namespace squeeze {

/// x with 3 significant digits, printf's "%.3g" (0.000428, 2.3e-05, 1.5e+03): the short form of
/// numbers in messages, reports and `squeeze check`'s tables. No errors (NaN prints "nan").
inline std::string format_g3(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

}  // namespace squeeze
