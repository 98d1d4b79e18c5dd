#!/usr/bin/env bash
# The whole test suite: sets up and builds (scripts/setup-debian.sh), then runs every test with ctest.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/scripts/setup-debian.sh"
build="${SQUEEZE_BUILD_DIR:-$here/build}"
ctest --test-dir "$build" --output-on-failure --parallel "$(nproc)" "$@"
