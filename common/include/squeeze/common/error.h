// squeeze::common — the three error tiers.
//  * InputError: bad input or configuration (missing file, broken mesh, NaN, impossible option).
//    Thrown; the CLI prints what() as one line and exits 1.
//  * Status values: expected numerical outcomes, returned, not thrown (each stage defines its own:
//    plan::PlanStatus, plan::Validity, ...).
//  * Programming errors: a caller that breaks a documented precondition of a function (a state
//    with the wrong number of rows handed to a renderer, a world used before prepare()) gets
//    std::logic_error or std::invalid_argument, checked in release builds too; the CLI reports
//    them as internal errors (exit 70). assert() is for invariants inside one function or class
//    that no caller can break, compiled out of release builds.
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
