#!/usr/bin/env python3
"""Writes a box [-0.5, 0.5]^3 split into nx*ny*nz cells of 6 tetrahedra (Kuhn/Freudenthal
subdivision, conforming, positively oriented) as a Medit .mesh file: the same mesh as
squeeze::fem::box_tet_mesh. Scale it to any box with a scene's transform.scale vector.

usage: box_mesh.py NX NY NZ OUT.mesh
"""
import itertools
import sys


def box_mesh(n):
    nx, ny, nz = n
    idx = lambda i, j, k: (k * (ny + 1) + j) * (nx + 1) + i
    V = [(-0.5 + i / nx, -0.5 + j / ny, -0.5 + k / nz)
         for k in range(nz + 1) for j in range(ny + 1) for i in range(nx + 1)]
    T = []
    for k, j, i in itertools.product(range(nz), range(ny), range(nx)):
        for perm in itertools.permutations(range(3)):
            c = [0, 0, 0]
            path = [idx(i, j, k)]
            for axis in perm:  # walk from corner 000 to 111 along the axes in this order
                c[axis] += 1
                path.append(idx(i + c[0], j + c[1], k + c[2]))
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


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    V, T = box_mesh([int(a) for a in sys.argv[1:4]])
    with open(sys.argv[4], "w") as f:
        f.write("MeshVersionFormatted 1\nDimension 3\nVertices\n%d\n" % len(V))
        for v in V:
            f.write("%.17g %.17g %.17g 0\n" % v)
        f.write("Tetrahedra\n%d\n" % len(T))
        for t in T:
            f.write("%d %d %d %d 1\n" % tuple(x + 1 for x in t))
        f.write("End\n")


if __name__ == "__main__":
    main()
