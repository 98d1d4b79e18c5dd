#!/usr/bin/env bash
# Builds squeeze's libFuzzer targets (fuzz/) with clang-14, AddressSanitizer and UBSan into
# build-fuzz/ (or $SQUEEZE_FUZZ_BUILD_DIR), and runs each for SECONDS (default 60) from its seed
# corpus (tests/fuzz/<target>/, copied to build-fuzz/corpus/<target>/, which keeps what the fuzzer
# finds between runs). Prints executions and coverage per target; exits 1 if any target found a
# crash, a leak, a timeout (10 s per input) or an input using more than 2 GB (the reproducer is
# build-fuzz/findings/<target>/), else 0.
# Usage: scripts/fuzz.sh [SECONDS] [TARGET...]      (as root, or with sudo available)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-60}"
shift || true
targets=("$@")
((${#targets[@]})) || targets=(fuzz_surface fuzz_tet_mesh fuzz_scene fuzz_plan)
build="${SQUEEZE_FUZZ_BUILD_DIR:-$here/build-fuzz}"

SQUEEZE_SETUP_PACKAGES_ONLY=1 "$here/scripts/setup-debian.sh"  # the packages only
missing=()
for p in clang-14 libfuzzer-14-dev libclang-rt-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "squeeze fuzz: installing ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
CC=clang-14 CXX=clang++-14 cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DSQUEEZE_BUILD_FUZZERS=ON -DSQUEEZE_BUILD_TESTS=OFF -DSQUEEZE_BUILD_BENCH=OFF "${launcher[@]}" >/dev/null
cmake --build "$build" --parallel "$(nproc)" --target "${targets[@]}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$here/tests/fuzz/lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
failed=0
summary=()
for t in "${targets[@]}"; do
  corpus="$build/corpus/$t" findings="$build/findings/$t"
  mkdir -p "$corpus" "$findings"
  cp -n "$here/tests/fuzz/$t/"* "$corpus/" 2>/dev/null || true
  log="$build/$t.log"
  echo "== $t: $seconds s" >&2
  set +e
  (cd "$findings" && "$build/fuzz/$t" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
     -print_final_stats=1 -artifact_prefix="$findings/" >"$log" 2>&1)
  rc=$?
  set -e
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*')
  ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*')
  found=$(ls "$findings" | wc -l)
  line="$t: ${execs:-?} executions, coverage ${cov:-?} edges (${ft:-?} features), corpus $(ls "$corpus" | wc -l) inputs, findings $found"
  if [ "$rc" -ne 0 ] || [ "$found" -ne 0 ]; then
    failed=1
    line="$line  FAILED (exit $rc; see $log and $findings)"
    grep -m 3 -E "ERROR: |runtime error|SUMMARY" "$log" >&2 || true
  fi
  summary+=("$line")
done
printf '%s\n' "${summary[@]}"
exit "$failed"
