#!/usr/bin/env bash
# The main job on the bundled default input: sets up and builds (scripts/setup-debian.sh), then runs
# `squeeze mesh` on the bundled Stanford bunny and writes its outputs to out/default/.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/scripts/setup-debian.sh"
build="${SQUEEZE_BUILD_DIR:-$here/build}"
out="${1:-$here/out/default}"
mkdir -p "$out"
"$build/squeeze" mesh "$here/scenes/assets/bunny.off" -o "$out/bunny.mesh" \
  --shells "$out/bunny_shells.off" --report "$out/bunny_report.json"
echo "squeeze: wrote $out/bunny.mesh (tetrahedra), $out/bunny_shells.off (convex shells), $out/bunny_report.json" >&2
