// The planner registry: one line names every planner, as X("name", ID). Each ID is defined as
// `std::unique_ptr<Planner> make_ID_planner()`: rrt in plan/src/rrt.cpp, the OMPL ones in
// plan/src/ompl_planners.cpp.
#include "squeeze/common/error.h"
#include "squeeze/plan/planner.h"

#define SQUEEZE_PLANNERS(X)                                                                                \
  X("rrt", rrt) X("ompl:RRT", ompl_rrt) X("ompl:KPIECE1", ompl_kpiece1) X("ompl:SST", ompl_sst) X("ompl:EST", ompl_est) \
  X("ompl:PDST", ompl_pdst)

namespace squeeze::plan {

#define SQUEEZE_DECLARE_PLANNER(NAME, ID) std::unique_ptr<Planner> make_##ID##_planner();
SQUEEZE_PLANNERS(SQUEEZE_DECLARE_PLANNER)
#undef SQUEEZE_DECLARE_PLANNER

namespace {
struct Entry {
  const char* name;
  std::unique_ptr<Planner> (*make)();
};
const std::vector<Entry>& registry() {
#define SQUEEZE_PLANNER_ENTRY(NAME, ID) Entry{NAME, &make_##ID##_planner},
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
