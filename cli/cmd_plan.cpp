// Placeholder until issue plan lands.
#include "commands.h"
#include "squeeze/common/error.h"

namespace squeeze::cli {
Runner add_plan_command(CLI::App& app, const Global&) {
  app.add_subcommand("plan", "Plan a motion (not implemented yet)");
  return [] () -> int { throw InputError("squeeze plan: not implemented yet"); };
}
Runner add_replay_command(CLI::App& app, const Global&) {
  app.add_subcommand("replay", "Replay a plan (not implemented yet)");
  return [] () -> int { throw InputError("squeeze replay: not implemented yet"); };
}
}  // namespace squeeze::cli
