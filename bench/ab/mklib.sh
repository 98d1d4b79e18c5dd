#!/bin/bash
# mklib.sh TREE OUT.so — the fem stage of source tree TREE (a checkout of squeeze) as a shared
# library for ab (see README.md). Headers of the other stages come from the same tree.
set -e
[ $# -eq 2 ] && [ -d "$1" ] || { echo "usage: mklib.sh TREE OUT.so (TREE: a squeeze checkout)" >&2; exit 2; }
R=$(cd "$1" && pwd); O=$2; H=$(cd "$(dirname "$0")" && pwd)
INC="-I$R/fem/include -I$R/meshing/include -I$R/common/include -I$R/ffd/include -isystem /usr/include/eigen3"
# Every fem source but the scene loader (which needs the whole meshing stage), and the meshing
# sources fem's Body needs: tet_quality.cpp in older trees; tet_faces.cpp, tet_geometry.cpp,
# tet_cleanup.cpp (with what it calls) since tet_quality.h was split.
FEM=$(ls "$R"/fem/src/*.cpp | grep -v '/scene\.cpp$')
MESHING=()
for f in tet_faces tet_geometry tet_cleanup tet_locator point_triangle_distance; do
  [ -f "$R/meshing/src/$f.cpp" ] && MESHING+=("$R/meshing/src/$f.cpp")
done
[ ${#MESHING[@]} -eq 0 ] && MESHING=("$R/meshing/src/tet_quality.cpp")
# shellcheck disable=SC2086
g++ -O3 -DNDEBUG -std=c++17 -fPIC -shared $INC -I"$R/fem/src" "$H/lib.cpp" $FEM "${MESHING[@]}" -o "$O" -ltbb
