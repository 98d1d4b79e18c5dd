#!/usr/bin/env python3
"""Voxel tetrahedral meshes for the bundled scenes: a set of grid cells, each split into 6
tetrahedra (Kuhn/Freudenthal subdivision with the same main diagonal in every cell, so the mesh is
conforming), positively oriented, written as Medit .mesh. Used for the plates and the walls of the
paper's environments (scenes/README.md says which file comes from which command).

usage: voxel_mesh.py box NX NY NZ OUT.mesh          box [-0.5, 0.5]^3 in NX*NY*NZ cells
       voxel_mesh.py plate_hole N HOLE OUT.mesh     N x 1 x N plate with a centred HOLE x HOLE opening
       voxel_mesh.py windows OUT.mesh               the four-chamber wall of the Windows scene
"""
import itertools
import sys


def kuhn(cells, size, origin=(0.0, 0.0, 0.0), h=(1.0, 1.0, 1.0)):
    """cells: set of (i, j, k); returns vertices (list of xyz) and tets (lists of 4 indices)."""
    index = {}
    V, T = [], []

    def vid(p):
        if p not in index:
            index[p] = len(V)
            V.append(tuple(origin[a] + p[a] * h[a] for a in range(3)))
        return index[p]

    for (i, j, k) in sorted(cells, key=lambda c: (c[2], c[1], c[0])):
        for perm in itertools.permutations(range(3)):
            c = [i, j, k]
            path = [vid(tuple(c))]
            for axis in perm:
                c[axis] += 1
                path.append(vid(tuple(c)))
            a, b, cc, d = (V[p] for p in path)
            u = [b[t] - a[t] for t in range(3)]
            v = [cc[t] - a[t] for t in range(3)]
            w = [d[t] - a[t] for t in range(3)]
            det = (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                   + u[2] * (v[0] * w[1] - v[1] * w[0]))
            if det < 0:
                path[2], path[3] = path[3], path[2]
            T.append(path)
    return V, T


def write(path, V, T):
    with open(path, "w") as f:
        f.write("MeshVersionFormatted 1\nDimension 3\nVertices\n%d\n" % len(V))
        for v in V:
            f.write("%.17g %.17g %.17g 0\n" % v)
        f.write("Tetrahedra\n%d\n" % len(T))
        for t in T:
            f.write("%d %d %d %d 1\n" % tuple(x + 1 for x in t))
        f.write("End\n")


def main():
    a = sys.argv[1:]
    if not a:
        sys.exit(__doc__)
    if a[0] == "box" and len(a) == 5:
        n = [int(x) for x in a[1:4]]
        cells = set(itertools.product(range(n[0]), range(n[1]), range(n[2])))
        V, T = kuhn(cells, n, (-0.5, -0.5, -0.5), tuple(1.0 / x for x in n))
        write(a[4], V, T)
    elif a[0] == "plate_hole" and len(a) == 4:
        n, hole = int(a[1]), int(a[2])
        lo = (n - hole) // 2
        cells = {(i, 0, k) for i in range(n) for k in range(n)
                 if not (lo <= i < lo + hole and lo <= k < lo + hole)}
        V, T = kuhn(cells, (n, 1, n), (-0.5, -0.5, -0.5), (1.0 / n, 1.0, 1.0 / n))
        write(a[3], V, T)
    elif a[0] == "windows" and len(a) == 2:
        # Model units = metres. Floor plan x, z in [-2, 2] (20 x 20 cells of 0.2 m), walls 0.2 m
        # thick along x = 0 and z = 0, 1.2 m high (6 cells). Chambers: A (x<0, z<0) start,
        # B (x>0, z<0) goal, C (x<0, z>0), D (x>0, z>0). Windows (cells removed), sills 0.2 m
        # above the floor: A|B 2x2 cells (0.4 m, the direct and smallest), A|C, C|D, D|B 3x3 (0.6 m).
        n, ny, mid = 20, 6, 10
        cells = set()
        for j in range(ny):
            for t in range(n):
                cells.add((mid, j, t))  # wall x in [0, 0.2): column i = 10
                cells.add((t, j, mid))  # wall z in [0, 0.2): row k = 10

        def cut(i_range, j_range, k_range):
            for c in itertools.product(i_range, j_range, k_range):
                cells.discard(c)

        cut([10], range(1, 3), range(4, 6))     # A|B: x wall at z in [-1.2, -0.8), 2 x 2
        cut(range(3, 6), range(1, 4), [10])     # A|C: z wall at x in [-1.4, -0.8), 3 x 3
        cut([10], range(1, 4), range(14, 17))   # C|D: x wall at z in [0.8, 1.4), 3 x 3
        cut(range(14, 17), range(1, 4), [10])   # D|B: z wall at x in [0.8, 1.4), 3 x 3
        V, T = kuhn(cells, (n, ny, n), (-2.0, 0.0, -2.0), (0.2, 0.2, 0.2))
        write(a[1], V, T)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
