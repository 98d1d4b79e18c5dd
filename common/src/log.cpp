#include "squeeze/common/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

namespace squeeze {
namespace {
Verbosity g_verbosity = Verbosity::normal;
}

void set_verbosity(Verbosity v) {
  g_verbosity = v;
  auto logger = spdlog::stderr_color_mt("squeeze");
  logger->set_pattern("squeeze: %^%l%$: %v");
  spdlog::set_default_logger(logger);
  switch (v) {
    case Verbosity::quiet: spdlog::set_level(spdlog::level::err); break;
    case Verbosity::normal: spdlog::set_level(spdlog::level::warn); break;
    case Verbosity::verbose: spdlog::set_level(spdlog::level::info); break;
    case Verbosity::debug: spdlog::set_level(spdlog::level::debug); break;
  }
}

Verbosity verbosity() { return g_verbosity; }

}  // namespace squeeze
