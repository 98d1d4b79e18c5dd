// Placeholder until issue render lands.
#include "commands.h"
#include "squeeze/common/error.h"

namespace squeeze::cli {
Runner add_render_command(CLI::App& app, const Global&) {
  app.add_subcommand("render", "Render a trajectory (not implemented yet)");
  return [] () -> int { throw InputError("squeeze render: not implemented yet"); };
}
}  // namespace squeeze::cli
