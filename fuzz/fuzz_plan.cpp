// libFuzzer target: the plan reader (plan::load_plan: JSON parsing and validation of a plan file).
#include "fuzz_common.h"
#include "squeeze/common/error.h"
#include "squeeze/plan/plan_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const auto path = squeeze::fuzz::put("plan.json", data, size);
  try {
    squeeze::plan::load_plan(path);
  } catch (const squeeze::InputError&) {
  }
  return 0;
}
