// squeeze::common — logging verbosity shared by every stage (spdlog, to stderr).
#pragma once

namespace squeeze {

/// Verbosity of the command line: -q (quiet: errors only), default (warnings and progress),
/// -v (info), -vv (debug).
enum class Verbosity { quiet, normal, verbose, debug };

/// Sets up spdlog's default logger on stderr at the level that matches `v`.
void set_verbosity(Verbosity v);
/// The verbosity last set (normal by default).
Verbosity verbosity();

}  // namespace squeeze
