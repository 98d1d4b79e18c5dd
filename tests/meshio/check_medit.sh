#!/usr/bin/env bash
# meshio reads squeeze's Medit (.mesh) files in double precision (MeshVersionFormatted 2) with the
# same points and tetrahedra as squeeze's own VTK XML export of the same mesh.
# Usage: tests/meshio/check_medit.sh SQUEEZE_BINARY MESH_INPUT
# Exit 77 (ctest: skipped) when Debian's python3-meshio is not installed.
set -euo pipefail
squeeze="$1"; input="$2"
py=/usr/bin/python3
if ! "$py" -c "import meshio" 2>/dev/null; then
  echo "skipped: meshio is not installed (Debian: apt-get install python3-meshio)"
  exit 77
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$squeeze" -q mesh "$input" --target-tets 200 -o "$work/a.mesh"
"$squeeze" -q mesh "$input" --target-tets 200 -o "$work/a.vtu"
"$py" - "$work/a.mesh" "$work/a.vtu" <<'PY'
import sys, meshio, numpy as np
m, v = meshio.read(sys.argv[1]), meshio.read(sys.argv[2])
assert m.points.dtype == np.float64, f"points read as {m.points.dtype}"
tm = [c.data for c in m.cells if c.type == "tetra"][0]
tv = [c.data for c in v.cells if c.type == "tetra"][0]
assert m.points.shape == v.points.shape and tm.shape == tv.shape, (m.points.shape, v.points.shape, tm.shape, tv.shape)
d = float(np.abs(m.points - v.points).max())
assert d == 0.0, f"points differ by {d}"
assert (tm == tv).all(), "tetrahedra differ"
print(f"ok: meshio {meshio.__version__} reads {sys.argv[1]} as {m.points.dtype}: {len(m.points)} points, {len(tm)} tetrahedra, identical to the .vtu")
PY
