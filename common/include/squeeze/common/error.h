// squeeze::common — the three error tiers.
//  * InputError: bad input or configuration (missing file, broken mesh, NaN, impossible option).
//    Thrown; the CLI prints what() as one line and exits non-zero.
//  * status enums: expected numerical outcomes (each stage defines its own).
//  * assert(): internal invariants.
#pragma once
#include <stdexcept>
#include <string>

namespace squeeze {

/// Bad input or configuration. what() is one line that names the file (or option) and the
/// problem, e.g. "bunny.obj: face 12 has a NaN coordinate".
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace squeeze
