#!/usr/bin/env bash
# The whole test suite: sets up and builds (scripts/setup-debian.sh), then runs every test with ctest.
# Usage: scripts/test.sh [CTEST ARGS...]
#        scripts/test.sh --sanitize [CTEST ARGS...]   the same with AddressSanitizer + UBSan: builds the
#          project (but bench/, which ctest does not run) and the test suite into build-sanitize/ (or
#          $SQUEEZE_SANITIZE_BUILD_DIR; RelWithDebInfo, -fsanitize=address,undefined) and runs ctest there; any report stops the test that made it
#          (halt_on_error). Suppressions of third-party reports: scripts/sanitize/*.supp (each documented).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ "${1:-}" = "--sanitize" ]; then
  shift
  SQUEEZE_SETUP_PACKAGES_ONLY=1 "$here/scripts/setup-debian.sh"
  build="${SQUEEZE_SANITIZE_BUILD_DIR:-$here/build-sanitize}"
  launcher=()
  command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSQUEEZE_SANITIZE=ON -DSQUEEZE_BUILD_BENCH=OFF "${launcher[@]}" >/dev/null
  cmake --build "$build" --parallel "$(nproc)"
  supp="$here/scripts/sanitize"
  export ASAN_OPTIONS="halt_on_error=1:abort_on_error=0:detect_leaks=1:strict_init_order=1:detect_stack_use_after_return=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
  export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=$supp/ubsan.supp${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
  export SQUEEZE_TEST_TIMEOUT_SCALE="${SQUEEZE_TEST_TIMEOUT_SCALE:-4}"  # tests' own limits on a squeeze run
  export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
  ctest --test-dir "$build" --output-on-failure --parallel "$(nproc)" "$@"
  exit
fi
"$here/scripts/setup-debian.sh"
build="${SQUEEZE_BUILD_DIR:-$here/build}"
ctest --test-dir "$build" --output-on-failure --parallel "$(nproc)" "$@"
