// The planner registry: one line names every planner. Each NAME is defined in plan/src/NAME.cpp
// as `std::unique_ptr<Planner> make_NAME_planner()`.
#include "squeeze/common/error.h"
#include "squeeze/plan/planner.h"

#define SQUEEZE_PLANNERS(X) X(rrt)

namespace squeeze::plan {

#define SQUEEZE_DECLARE_PLANNER(NAME) std::unique_ptr<Planner> make_##NAME##_planner();
SQUEEZE_PLANNERS(SQUEEZE_DECLARE_PLANNER)
#undef SQUEEZE_DECLARE_PLANNER

namespace {
struct Entry {
  const char* name;
  std::unique_ptr<Planner> (*make)();
};
const std::vector<Entry>& registry() {
#define SQUEEZE_PLANNER_ENTRY(NAME) Entry{#NAME, &make_##NAME##_planner},
  static const std::vector<Entry> table = {SQUEEZE_PLANNERS(SQUEEZE_PLANNER_ENTRY)};
#undef SQUEEZE_PLANNER_ENTRY
  return table;
}
}  // namespace

std::vector<std::string> planner_names() {
  std::vector<std::string> names;
  for (const Entry& e : registry()) names.emplace_back(e.name);
  return names;
}

std::unique_ptr<Planner> make_planner(const std::string& name) {
  for (const Entry& e : registry())
    if (name == e.name) return e.make();
  std::string list;
  for (const Entry& e : registry()) list += (list.empty() ? "\"" : ", \"") + std::string(e.name) + "\"";
  throw InputError("planner.algorithm: unknown planner \"" + name + "\" (known: " + list + ")");
}

}  // namespace squeeze::plan
