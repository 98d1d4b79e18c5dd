#!/bin/bash
# mklib.sh TREE OUT.so — the fem stage of source tree TREE (a checkout of squeeze) as a shared
# library for ab (see README.md). Headers of the other stages come from the same tree.
set -e
[ $# -eq 2 ] && [ -d "$1" ] || { echo "usage: mklib.sh TREE OUT.so (TREE: a squeeze checkout)" >&2; exit 2; }
R=$(cd "$1" && pwd); O=$2; H=$(cd "$(dirname "$0")" && pwd)
INC="-I$R/fem/include -I$R/meshing/include -I$R/common/include -I$R/ffd/include -isystem /usr/include/eigen3"
g++ -O3 -DNDEBUG -std=c++17 -fPIC -shared $INC "$H/lib.cpp" "$R/fem/src/world.cpp" "$R/fem/src/body.cpp" \
  "$R/fem/src/collision.cpp" "$R/meshing/src/tet_quality.cpp" -o "$O" -ltbb
