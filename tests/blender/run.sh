#!/usr/bin/env bash
# The Blender check of squeeze's exports (docs/render.md, "Blender"), for every bundled scene:
# `squeeze simulate` (DURATION s), `squeeze render --no-png --export obj,pc2,mdd,glb` of the whole
# path and of a partial range, then check_exports.py in headless Blender.
# Usage: tests/blender/run.sh SQUEEZE_BINARY SCENES_DIR [DURATION]
# Exit 77 (ctest: skipped) when Blender is not installed (Debian: apt-get install blender).
set -euo pipefail
squeeze="$1"; scenes="$2"; duration="${3:-0.5}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
if ! command -v blender >/dev/null 2>&1; then
  echo "skipped: blender is not installed (Debian: apt-get install blender)"
  exit 77
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
fps=30
for scene in "$scenes"/*.json; do
  name="$(basename "$scene" .json)"
  echo "== $name"
  "$squeeze" -q simulate "$scene" --duration "$duration" --fps "$fps" -o "$work/$name"
  full="$work/$name-render"
  "$squeeze" -q render "$scene" "$work/$name" -o "$full" --no-png --no-plots --export obj,pc2,mdd,glb
  first_object="$(ls "$full/export" | grep '\.pc2$' | head -1)"
  frames=$(ls "$full/export/obj" | grep -c "^${first_object%.pc2}_[0-9]*\.obj$")
  render_fps=$(python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j.get('render',{}).get('fps',$fps))" "$scene")
  last=$((frames - 1))
  for range in "0-$last" "$((last / 2))-$last"; do
    out="$full"
    if [ "$range" != "0-$last" ]; then
      out="$work/$name-render-part"
      "$squeeze" -q render "$scene" "$work/$name" -o "$out" --no-png --no-plots --export obj,pc2,mdd,glb --frames "$range"
    fi
    blender -b --factory-startup --python-exit-code 1 --python "$here/check_exports.py" -- \
      "$out/export" "${range%-*}" "${range#*-}" "$render_fps" 2>&1 | grep -E "^(ok|blender check|Error|Traceback|RuntimeError|  File)" || {
      echo "FAILED: $name frames $range"; exit 1; }
  done
done
echo "blender check: every bundled scene passed"
