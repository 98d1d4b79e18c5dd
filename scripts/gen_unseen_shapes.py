#!/usr/bin/env python3
"""Writes the generated shapes of docs/meshing.md, "Version 9", as OFF/OBJ files into DIR.

Usage: scripts/gen_unseen_shapes.py DIR [--elephant PATH/elephant.off]
Shapes (metres): trefoil.off (knot tube), torus.off, torus_mm.off (x1000), torus_tiny.off (x0.001),
lbracket.off, pipe.off (3 mm wall), spheres40.off (40 separate spheres), hemishell.off (4 mm wall),
bowl1mm.off, leg.off (10-segment cylinder), spider.obj (+ .mtl: body, head, 8 legs through the
body); with --elephant, elephant_holes_{0.01,0.02,0.03}.off (six holes of that radius, as a fraction
of the diagonal, around seeded random vertices). Then: scripts/mesh_matrix.py DIR/*.off DIR/*.obj
With --version24, the shapes of docs/meshing.md, "Version 24", instead: staircase, comb (12 teeth
2 mm thick, 4 mm apart), urchin (20 spikes), washer (1 mm), bottle (1.5 mm wall, open neck) and
bottle_pinhole (a 4 mm hole through its base), spiral (3 mm wall, 3 turns), plate_cubes (a 1 m
plate and ten 1 cm cubes), hollow_box (3 mm wall), ribbon (2 mm, one twist), star (7 points),
hollow_sphere (2 mm), hollow_torus (3 mm), can (1 mm), egg_shell (7-25 mm wall).
With --version26, those of "Version 26": wavy_curtain (1 x 2 m, 1 cm, waved), figure8_knot,
torus_knot25 (a (2,5) torus knot), slot_jaws (two boxes 5 cm apart), gear (24 teeth, 1 cm),
spring (6 turns of 5 mm wire, open ends capped), table (a top and four legs through it), chain
(four linked tori), single_quad (two triangles), open_box (no lid, zero thickness),
rotated_thin_box (1 x 0.6 x 0.02 m, turned and moved 100 m), inside_out_sphere, two_cubes_touching,
rod (2 m, 2 cm across, 16 sides, one ring), sphere_holes (five holes).
"""
import argparse
import os

import numpy as np


def write_off(fn, V, F):
    with open(fn, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(V), len(F)))
        for v in V:
            f.write("%.9g %.9g %.9g\n" % tuple(v))
        for t in F:
            f.write("3 %d %d %d\n" % tuple(t))


def tube(curve, dcurve, r, n, m, T=None):
    """A tube of radius r and m sides around curve(t): closed (T None: n rings over t in [0, 2 pi),
    the last joined to the first), or open (n + 1 rings over t in [0, T], each end capped by a fan
    around its centre)."""
    rings = n if T is None else n + 1
    V, F = [], []
    for i in range(rings):
        t = 2 * np.pi * i / n if T is None else T * i / n
        c, d = curve(t), dcurve(t)
        d = d / np.linalg.norm(d)
        a = np.array([0, 0, 1.0]) if abs(d[2]) < 0.9 else np.array([1.0, 0, 0])
        u = np.cross(d, a)
        u /= np.linalg.norm(u)
        w = np.cross(d, u)
        for j in range(m):
            s = 2 * np.pi * j / m
            V.append(c + r * (np.cos(s) * u + np.sin(s) * w))
    for i in range(n):
        for j in range(m):
            a, b = i * m + j, ((i + 1) % rings) * m + j
            c, d = ((i + 1) % rings) * m + (j + 1) % m, i * m + (j + 1) % m
            F += [(a, b, c), (a, c, d)]
    if T is not None:
        V += [curve(0), curve(T)]
        c0, c1 = len(V) - 2, len(V) - 1
        for j in range(m):
            F += [(c0, (j + 1) % m, j), (c1, n * m + j, n * m + (j + 1) % m)]
    return np.array(V), F


def shell(R, th, nu, nv):
    """A closed hemispherical shell: outer radius R, wall th, rim closed by a band."""
    V, F = [], []
    for r in (R, R - th):
        V.append((0, 0, r))
        for k in range(1, nv + 1):
            z, rr = r * np.cos(np.pi / 2 * k / nv), r * np.sin(np.pi / 2 * k / nv)
            V += [(rr * np.cos(2 * np.pi * j / nu), rr * np.sin(2 * np.pi * j / nu), z) for j in range(nu)]
    no = 1 + nv * nu

    def idx(s, k, j):
        return s * no + (0 if k == 0 else 1 + (k - 1) * nu + j % nu)

    for s, flip in ((0, False), (1, True)):
        for j in range(nu):
            t = (idx(s, 0, 0), idx(s, 1, j), idx(s, 1, j + 1))
            F.append(t[::-1] if flip else t)
        for k in range(1, nv):
            for j in range(nu):
                a, b, c, d = idx(s, k, j), idx(s, k + 1, j), idx(s, k + 1, j + 1), idx(s, k, j + 1)
                for t in ((a, b, c), (a, c, d)):
                    F.append(t[::-1] if flip else t)
    for j in range(nu):
        a, b, c, d = idx(0, nv, j), idx(1, nv, j), idx(1, nv, j + 1), idx(0, nv, j + 1)
        F += [(a, b, c), (a, c, d)]
    return np.array(V), F


def cylinder(p0, p1, r, nu=10):
    d = p1 - p0
    d = d / np.linalg.norm(d)
    a = np.array([0, 0, 1.0]) if abs(d[2]) < 0.9 else np.array([1.0, 0, 0])
    u = np.cross(d, a)
    u /= np.linalg.norm(u)
    w = np.cross(d, u)
    V, F = [p0, p1], []
    for end in (p0, p1):
        for j in range(nu):
            s = 2 * np.pi * j / nu
            V.append(end + r * (np.cos(s) * u + np.sin(s) * w))
    for j in range(nu):
        a0, a1, b0, b1 = 2 + j, 2 + (j + 1) % nu, 2 + nu + j, 2 + nu + (j + 1) % nu
        F += [(0, a1, a0), (1, b0, b1), (a0, a1, b1), (a0, b1, b0)]
    return np.array(V), F


def uv_sphere(c, scale, nu=16, nv=10):
    V = [np.array([0, 0, 1.0])]
    for k in range(1, nv):
        th = np.pi * k / nv
        for j in range(nu):
            a = 2 * np.pi * j / nu
            V.append(np.array([np.sin(th) * np.cos(a), np.sin(th) * np.sin(a), np.cos(th)]))
    V.append(np.array([0, 0, -1.0]))
    n = len(V)

    def idx(k, j):
        return 1 + (k - 1) * nu + j % nu

    F = [(0, idx(1, j), idx(1, j + 1)) for j in range(nu)]
    for k in range(1, nv - 1):
        for j in range(nu):
            a, b, cc, d = idx(k, j), idx(k + 1, j), idx(k + 1, j + 1), idx(k, j + 1)
            F += [(a, b, cc), (a, cc, d)]
    F += [(n - 1, idx(nv - 1, j + 1), idx(nv - 1, j)) for j in range(nu)]
    return np.array(V) * np.array(scale) + c, F


def earclip(P):
    """Triangles of a simple counter-clockwise polygon (a list of (x, y)), fattest ear first."""
    P = [np.array(p, float) for p in P]
    idx = list(range(len(P)))
    cross = lambda o, a, b: (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    T = []
    while len(idx) > 3:
        n, best = len(idx), None
        for k in range(n):
            i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % n]
            a, b, c = P[i0], P[i1], P[i2]
            if cross(a, b, c) <= 1e-15:
                continue
            if any(cross(a, b, P[j]) >= 0 and cross(b, c, P[j]) >= 0 and cross(c, a, P[j]) >= 0
                   for j in idx if j not in (i0, i1, i2)):
                continue
            q = cross(a, b, c) / (np.linalg.norm(b - a) * np.linalg.norm(c - b) * np.linalg.norm(a - c))
            if best is None or q > best[0]:
                best = (q, k)
        k = best[1]
        T.append((idx[k - 1], idx[k], idx[(k + 1) % n]))
        idx.pop(k)
    return T + [tuple(idx)]


def extrude(P, h, z0=0.0):
    n, T = len(P), earclip(P)
    V = [(x, y, z0) for x, y in P] + [(x, y, z0 + h) for x, y in P]
    F = [(a, c, b) for a, b, c in T] + [(a + n, b + n, c + n) for a, b, c in T]
    for i in range(n):
        j = (i + 1) % n
        F += [(i, j, j + n), (i, j + n, i + n)]
    return np.array(V), F


def revolve(prof, nu):
    """The surface of revolution about z of a closed (r, z) polygon, counter-clockwise, r > 0 (a
    ring), or of a polyline from the axis to the axis (r = 0 at both ends: a solid)."""
    V, F, ids = [], [], {}
    closed = prof[0][0] > 0

    def vid(i, j):
        r, z = prof[i % len(prof)]
        key = ("axis", i) if r == 0 else (i % len(prof), j % nu)
        if key not in ids:
            a = 2 * np.pi * (j % nu) / nu
            ids[key] = len(V)
            V.append((r * np.cos(a), r * np.sin(a), z))
        return ids[key]

    for j in range(nu):
        for i in range(len(prof) if closed else len(prof) - 1):
            a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
            F += [t for t in ((a, c, b), (a, d, c)) if len(set(t)) == 3]
    return np.array(V), F


def merge(*parts):
    V, F = [], []
    for v, f in parts:
        F += [(a + len(V), b + len(V), c + len(V)) for a, b, c in f]
        V += list(v)
    return np.array(V), F


def box(lo, hi):
    V = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    F = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1), (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4),
         (1, 5, 7), (1, 7, 3)]
    return V, F


def inward(vf):
    return vf[0], [(a, c, b) for a, b, c in vf[1]]


def version24(out):
    P = [(0, 0), (1.6, 0), (1.6, 1.2)]
    for i in range(8, 1, -1):
        P += [(0.2 * (i - 1), 0.15 * i), (0.2 * (i - 1), 0.15 * (i - 1))]
    write_off(out("staircase.off"), *extrude(P + [(0, 0.15)], 1.0))
    P = [(0, 0), (0.072, 0), (0.072, 0.01)]
    for k in range(11, -1, -1):
        x0 = k * 0.006 + 0.002
        P += [(x0 + 0.002, 0.01), (x0 + 0.002, 0.06), (x0, 0.06), (x0, 0.01)]
    write_off(out("comb.off"), *extrude(P + [(0, 0.01)], 0.03))
    V, F = uv_sphere(np.zeros(3), (1, 1, 1), 64, 40)
    D = np.random.default_rng(7).normal(size=(20, 3))
    D /= np.linalg.norm(D, axis=1)[:, None]
    N = V / np.linalg.norm(V, axis=1)[:, None]
    s = np.clip((N @ D.T - 0.97) / 0.03, 0, None).max(1)
    write_off(out("urchin.off"), N * (0.1 * (1 + 1.5 * s ** 2))[:, None], F)
    write_off(out("washer.off"), *revolve([(0.01, 0), (0.03, 0), (0.03, 0.001), (0.01, 0.001)], 96))
    neck = [(0.04, 0), (0.04, 0.15), (0.015, 0.19), (0.015, 0.23), (0.0135, 0.23), (0.0135, 0.1906), (0.0385, 0.1494),
            (0.0385, 0.0015)]
    write_off(out("bottle.off"), *revolve([(0, 0)] + neck + [(0, 0.0015)], 64))
    write_off(out("bottle_pinhole.off"), *revolve([(0.002, 0)] + neck + [(0.002, 0.0015)], 64))
    t = np.linspace(0, 6 * np.pi, 300)
    r = 0.05 + 0.02 * t / (2 * np.pi)
    P = [((q - 0.0015) * np.cos(a), (q - 0.0015) * np.sin(a)) for q, a in zip(r, t)]
    P += [((q + 0.0015) * np.cos(a), (q + 0.0015) * np.sin(a)) for q, a in zip(r[::-1], t[::-1])]
    write_off(out("spiral.off"), *extrude(P[::-1], 0.05))
    parts = [extrude([(0, 0), (1, 0), (1, 1), (0, 1)], 0.02)]
    for i in range(10):
        x = 0.05 + 0.09 * i
        parts.append(extrude([(x, 0.5), (x + 0.01, 0.5), (x + 0.01, 0.51), (x, 0.51)], 0.01, 0.03))
    write_off(out("plate_cubes.off"), *merge(*parts))
    write_off(out("hollow_box.off"), *merge(box((0, 0, 0), (0.3, 0.3, 0.3)), inward(box((0.003,) * 3, (0.297,) * 3))))
    n, V, F = 200, [], []
    sec = [(-0.025, -0.001), (0.025, -0.001), (0.025, 0.001), (-0.025, 0.001)]
    for i in range(n + 1):
        x, a = i / n, 2 * np.pi * i / n
        V += [(x, u * np.cos(a) - v * np.sin(a), u * np.sin(a) + v * np.cos(a)) for u, v in sec]
    for i in range(n):
        for k in range(4):
            a, b, c, d = i * 4 + k, i * 4 + (k + 1) % 4, (i + 1) * 4 + (k + 1) % 4, (i + 1) * 4 + k
            F += [(a, b, c), (a, c, d)]
    F += [(0, 2, 1), (0, 3, 2), (4 * n, 4 * n + 1, 4 * n + 2), (4 * n, 4 * n + 2, 4 * n + 3)]
    write_off(out("ribbon.off"), np.array(V), F)
    P = [((1.0 if k % 2 == 0 else 0.15) * np.cos(np.pi * k / 7), (1.0 if k % 2 == 0 else 0.15) * np.sin(np.pi * k / 7))
         for k in range(14)]
    write_off(out("star.off"), *extrude(P, 0.2))
    write_off(out("hollow_sphere.off"),
              *merge(uv_sphere(np.zeros(3), (0.2,) * 3, 48, 32), inward(uv_sphere(np.zeros(3), (0.198,) * 3, 48, 32))))
    tor = lambda t: np.array([0.3 * np.cos(t), 0.3 * np.sin(t), 0])
    dtor = lambda t: np.array([-np.sin(t), np.cos(t), 0])
    write_off(out("hollow_torus.off"), *merge(tube(tor, dtor, 0.05, 96, 24), inward(tube(tor, dtor, 0.047, 96, 24))))
    write_off(out("can.off"), *merge(cylinder(np.zeros(3), np.array([0, 0, 0.12]), 0.05, 48),
                                     inward(cylinder(np.array([0, 0, 0.001]), np.array([0, 0, 0.119]), 0.049, 48))))
    write_off(out("egg_shell.off"), *merge(uv_sphere(np.zeros(3), (0.3, 0.2, 0.15), 48, 32),
                                           inward(uv_sphere(np.array([0.01, 0, 0]), (0.285, 0.19, 0.143), 48, 32))))


def version26(out):
    """The shapes tried in the twenty-ninth session (docs/meshing.md, "Version 26")."""
    rng = np.random.default_rng(7)
    def grid_sheet(f, nx, ny, th):
        # closed thin sheet around the surface (x,y)->f(x,y) in [0,1]^2 scaled; thickness th along z
        V = []
        for s in (0, 1):
            for i in range(nx + 1):
                for j in range(ny + 1):
                    x, y = i / nx, j / ny
                    p = np.array(f(x, y)); p[2] += (th / 2 if s else -th / 2); V.append(p)
        idx = lambda s, i, j: s * (nx + 1) * (ny + 1) + i * (ny + 1) + j
        F = []
        for i in range(nx):
            for j in range(ny):
                a, b, c, d = idx(1, i, j), idx(1, i + 1, j), idx(1, i + 1, j + 1), idx(1, i, j + 1)
                F += [(a, b, c), (a, c, d)]
                a, b, c, d = idx(0, i, j), idx(0, i + 1, j), idx(0, i + 1, j + 1), idx(0, i, j + 1)
                F += [(a, c, b), (a, d, c)]
        ring = [(i, 0) for i in range(nx)] + [(nx, j) for j in range(ny)] + [(i, ny) for i in range(nx, 0, -1)] + [(0, j) for j in range(ny, 0, -1)]
        for k in range(len(ring)):
            (i0, j0), (i1, j1) = ring[k], ring[(k + 1) % len(ring)]
            a, b, c, d = idx(0, i0, j0), idx(0, i1, j1), idx(1, i1, j1), idx(1, i0, j0)
            F += [(a, b, c), (a, c, d)]
        return np.array(V), F

    write_off(out("wavy_curtain.off"), *grid_sheet(lambda x, y: (x, 2 * y, 0.1 * np.sin(2 * np.pi * x / 0.5)), 40, 8, 0.01))

    f8 = lambda t: np.array([(2 + np.cos(2 * t)) * np.cos(3 * t), (2 + np.cos(2 * t)) * np.sin(3 * t), np.sin(4 * t)]) * 0.1
    df8 = lambda t, h=1e-5: (f8(t + h) - f8(t - h)) / (2 * h)
    write_off(out("figure8_knot.off"), *tube(f8, df8, 0.03, 240, 12))
    tk = lambda t: np.array([(1 + 0.4 * np.cos(5 * t)) * np.cos(2 * t), (1 + 0.4 * np.cos(5 * t)) * np.sin(2 * t), 0.4 * np.sin(5 * t)])
    dtk = lambda t, h=1e-5: (tk(t + h) - tk(t - h)) / (2 * h)
    write_off(out("torus_knot25.off"), *tube(tk, dtk, 0.05, 400, 10))

    write_off(out("slot_jaws.off"), *merge(box((0, 0, 0), (0.3, 0.5, 0.1)), box((0.35, 0, 0), (0.65, 0.5, 0.1))))

    P = []
    for k in range(24):
        for a, r in ((0.0, 0.09), (0.3, 0.09), (0.45, 0.1), (0.75, 0.1)):
            t = 2 * np.pi * (k + a) / 24
            P.append((r * np.cos(t), r * np.sin(t)))
    write_off(out("gear.off"), *extrude(P, 0.01))

    hel = lambda t: np.array([0.05 * np.cos(t), 0.05 * np.sin(t), 0.2 * t / (12 * np.pi)])
    dhel = lambda t, h=1e-5: (hel(t + h) - hel(t - h)) / (2 * h)
    write_off(out("spring.off"), *tube(hel, dhel, 0.005, 360, 10, 12 * np.pi))

    parts = [box((0, 0, 0.7), (1.2, 0.8, 0.74))]
    for x, y in ((0.05, 0.05), (1.1, 0.05), (0.05, 0.7), (1.1, 0.7)):
        parts.append(box((x, y, 0), (x + 0.05, y + 0.05, 0.72)))
    write_off(out("table.off"), *merge(*parts))

    def torus(c, R, r, axis, nu=32, nv=12):
        V, F = [], []
        for i in range(nu):
            a = 2 * np.pi * i / nu
            for j in range(nv):
                b = 2 * np.pi * j / nv
                p = np.array([(R + r * np.cos(b)) * np.cos(a), (R + r * np.cos(b)) * np.sin(a), r * np.sin(b)])
                if axis == 1: p = np.array([p[0], p[2], p[1]])
                V.append(p + c)
        for i in range(nu):
            for j in range(nv):
                a, b = i * nv + j, ((i + 1) % nu) * nv + j
                cc, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
                F += [(a, b, cc), (a, cc, d)] if axis == 0 else [(a, cc, b), (a, d, cc)]
        return np.array(V), F
    write_off(out("chain.off"), *merge(*[torus(np.array([0.15 * k, 0, 0]), 0.1, 0.02, k % 2) for k in range(4)]))

    write_off(out("single_quad.off"), np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]]), [(0, 1, 2), (0, 2, 3)])
    V, F = box((0, 0, 0), (1, 1, 1)); F = [f for f in F if not all(V[i][2] == 1 for i in f)]
    write_off(out("open_box.off"), V, F)

    V, F = box((0, 0, 0), (1, 0.6, 0.02))
    ax = np.array([1, 2, 3.0]); ax /= np.linalg.norm(ax); th = 0.7
    K = np.array([[0, -ax[2], ax[1]], [ax[2], 0, -ax[0]], [-ax[1], ax[0], 0]])
    Rm = np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K
    write_off(out("rotated_thin_box.off"), V @ Rm.T + np.array([100, -40, 7.0]), F)

    write_off(out("inside_out_sphere.off"), *inward(uv_sphere(np.zeros(3), (0.3, 0.3, 0.3), 32, 16)))
    write_off(out("two_cubes_touching.off"), *merge(box((0, 0, 0), (1, 1, 1)), box((1, 0, 0), (2, 1, 1))))
    write_off(out("rod.off"), *cylinder(np.array([0, 0, 0.0]), np.array([2, 0, 0.0]), 0.01, 16))

    V, F = uv_sphere(np.zeros(3), (1, 1, 1), 64, 32)
    bad = set()
    for k in range(5):
        c = V[rng.integers(len(V))]
        bad |= {fi for fi, f in enumerate(F) if np.linalg.norm(V[list(f)].mean(0) - c) < 0.12}
    write_off(out("sphere_holes.off"), V, [f for fi, f in enumerate(F) if fi not in bad])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir")
    ap.add_argument("--elephant", help="the corpus elephant.off, to cut holes into")
    ap.add_argument("--version24", action="store_true", help="the shapes of version 24 instead")
    ap.add_argument("--version26", action="store_true", help="the shapes of version 26 instead")
    args = ap.parse_args()
    if args.elephant and not os.path.isfile(args.elephant):
        ap.error("--elephant: no such file: " + args.elephant)
    os.makedirs(args.dir, exist_ok=True)
    out = lambda name: os.path.join(args.dir, name)
    if args.version24:
        version24(out)
        return
    if args.version26:
        version26(out)
        return

    tre = lambda t: 0.1 * np.array([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)])
    dtre = lambda t: 0.1 * np.array([np.cos(t) + 4 * np.cos(2 * t), -np.sin(t) + 4 * np.sin(2 * t), -3 * np.cos(3 * t)])
    write_off(out("trefoil.off"), *tube(tre, dtre, 0.05, 300, 16))
    tor = lambda t: np.array([0.3 * np.cos(t), 0.3 * np.sin(t), 0])
    dtor = lambda t: np.array([-np.sin(t), np.cos(t), 0])
    V, F = tube(tor, dtor, 0.08, 96, 24)
    write_off(out("torus.off"), V, F)
    write_off(out("torus_mm.off"), V * 1000, F)
    write_off(out("torus_tiny.off"), V * 0.001, F)
    write_off(out("hemishell.off"), *shell(0.2, 0.004, 48, 12))
    write_off(out("bowl1mm.off"), *shell(0.1, 0.001, 64, 16))

    P = [(0, 0), (0.3, 0), (0.3, 0.02), (0.02, 0.02), (0.02, 0.2), (0, 0.2)]
    V = [(x, y, 0) for x, y in P] + [(x, y, 0.15) for x, y in P]
    F = [(0, 2, 1), (0, 3, 2), (0, 5, 3), (5, 4, 3)]
    F = F + [(c + 6, b + 6, a + 6) for a, b, c in F]
    for i in range(6):
        j = (i + 1) % 6
        F += [(i, j, j + 6), (i, j + 6, i + 6)]
    write_off(out("lbracket.off"), np.array(V, float), F)

    ro, ri, L, nu, nz = 0.05, 0.047, 0.5, 40, 20
    V, F = [], []
    for k in range(nz + 1):
        z = L * k / nz
        V += [(ro * np.cos(2 * np.pi * j / nu), ro * np.sin(2 * np.pi * j / nu), z) for j in range(nu)]
        V += [(ri * np.cos(2 * np.pi * j / nu), ri * np.sin(2 * np.pi * j / nu), z) for j in range(nu)]
    o = lambda k, j: k * 2 * nu + j % nu
    i_ = lambda k, j: k * 2 * nu + nu + j % nu
    for k in range(nz):
        for j in range(nu):
            a, b, c, d = o(k, j), o(k, j + 1), o(k + 1, j + 1), o(k + 1, j)
            F += [(a, b, c), (a, c, d)]
            a, b, c, d = i_(k, j), i_(k, j + 1), i_(k + 1, j + 1), i_(k + 1, j)
            F += [(a, c, b), (a, d, c)]
    for j in range(nu):
        a, b, c, d = o(0, j), o(0, j + 1), i_(0, j + 1), i_(0, j)
        F += [(a, c, b), (a, d, c)]
        a, b, c, d = o(nz, j), o(nz, j + 1), i_(nz, j + 1), i_(nz, j)
        F += [(a, b, c), (a, c, d)]
    write_off(out("pipe.off"), np.array(V), F)

    rng = np.random.default_rng(3)
    V, F = [], []
    for _ in range(40):
        c, r = rng.uniform(-0.5, 0.5, 3), rng.uniform(0.02, 0.06)
        v, f = uv_sphere(c, (r, r, r), 12, 8)
        F += [(x + len(V), y + len(V), z + len(V)) for x, y, z in f]
        V += list(v)
    write_off(out("spheres40.off"), np.array(V), F)

    write_off(out("leg.off"), *cylinder(np.array([0, 0, 0.05]), np.array([0.08, -0.12, 0.25]), 0.012))
    parts = [("body",) + uv_sphere(np.zeros(3), (0.12, 0.08, 0.1)),
             ("head",) + uv_sphere(np.array([0.15, 0, 0]), (0.06, 0.05, 0.05))]
    for i in range(8):
        side, k = (1 if i < 4 else -1), i % 4
        x = -0.06 + 0.045 * k
        p0, p1 = np.array([x, 0, side * 0.05]), np.array([x + 0.08 * (k - 1.5) / 1.5, -0.12, side * 0.25])
        parts.append(("leg%d" % i,) + cylinder(p0, p1, 0.012))
    with open(out("spider.mtl"), "w") as f:
        for n in ("shell", "leg"):
            f.write("newmtl %s\nKd 0.3 0.2 0.1\n" % n)
    with open(out("spider.obj"), "w") as f:
        f.write("mtllib spider.mtl\n")
        off = 1
        for name, V, F in parts:
            f.write("o %s\nusemtl %s\n" % (name, "leg" if "leg" in name else "shell"))
            for v in V:
                f.write("v %.6f %.6f %.6f\n" % tuple(v))
            for t in F:
                f.write("f %d %d %d\n" % (t[0] + off, t[1] + off, t[2] + off))
            off += len(V)

    if args.elephant:
        L = open(args.elephant).read().split()
        nv, nf = int(L[1]), int(L[2])
        V = np.array(L[4:4 + 3 * nv], float).reshape(-1, 3)
        F = np.array(L[4 + 3 * nv:4 + 3 * nv + 4 * nf], int).reshape(-1, 4)[:, 1:]
        diag = np.linalg.norm(V.max(0) - V.min(0))
        for rad in (0.01, 0.02, 0.03):
            rng = np.random.default_rng(5)
            keep = np.ones(len(F), bool)
            for _ in range(6):
                p = V[rng.integers(len(V))]
                keep &= np.linalg.norm(V[F].mean(1) - p, axis=1) > rad * diag
            write_off(out("elephant_holes_%g.off" % rad), V, F[keep])


if __name__ == "__main__":
    main()
