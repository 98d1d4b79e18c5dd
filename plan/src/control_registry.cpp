// The control registry: one line names every manipulation force, in sampling order. Each NAME is
// defined in plan/src/controls/NAME.cpp as `const ControlKind& NAME_control()`.
#include "squeeze/plan/control.h"

#define SQUEEZE_CONTROL_KINDS(X) X(body) X(control_point) X(interpolation) X(squeeze)

namespace squeeze::plan {

#define SQUEEZE_DECLARE_KIND(NAME) const ControlKind& NAME##_control();
SQUEEZE_CONTROL_KINDS(SQUEEZE_DECLARE_KIND)
#undef SQUEEZE_DECLARE_KIND

const std::vector<const ControlKind*>& control_kinds() {
#define SQUEEZE_KIND_ENTRY(NAME) &NAME##_control(),
  static const std::vector<const ControlKind*> kinds = {SQUEEZE_CONTROL_KINDS(SQUEEZE_KIND_ENTRY)};
#undef SQUEEZE_KIND_ENTRY
  return kinds;
}

}  // namespace squeeze::plan
