#!/usr/bin/python3
"""Writes grain.geo: an irregular, angular rock grain for cases/grain_crushing_3d.

    cases/grain_crushing_3d/make_grain.py [--seed S] [--radius R] [--out grain.geo]

The grain is an icosahedron subdivided once (42 vertices, 80 triangular faces) whose vertices are
moved radially by a random factor in [0.8, 1.2] and then stretched to semi-axes (1, 0.85, 0.7) R:
a faceted, elongated, star-shaped polyhedron (so its surface cannot intersect itself). Every face
is a plane triangle of Gmsh's built-in kernel; the volume is the physical group "grain", the
surface the node set "surface". The points carry a large size (R): the case caps the element size
with mesh.element_size. Prints the grain's extent in z, which the case file uses for its platens.
"""
import argparse
import math
import random


def icosphere():
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
         (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    mid = {}

    def midpoint(a, b):
        key = (min(a, b), max(a, b))
        if key not in mid:
            p = [(v[a][k] + v[b][k]) / 2 for k in range(3)]
            n = math.sqrt(sum(x * x for x in p))
            v.append(tuple(x / n for x in p))
            mid[key] = len(v) - 1
        return mid[key]

    out = []
    for a, b, c in f:
        ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
        out += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    return v, out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--radius", type=float, default=0.025)
    ap.add_argument("--out", default="grain.geo")
    a = ap.parse_args()
    rnd = random.Random(a.seed)
    v, faces = icosphere()
    axes = (1.0, 0.85, 0.7)
    pts = []
    for p in v:
        r = a.radius * rnd.uniform(0.8, 1.2)
        pts.append(tuple(r * p[k] * axes[k] for k in range(3)))
    # faces are oriented outwards (the icosphere's are; radial moves keep the grain star-shaped)
    lines = {}
    out = ["// Irregular rock grain, written by make_grain.py --seed %d --radius %g" % (a.seed, a.radius),
           "// (icosahedron subdivided once, vertices moved radially by [0.8, 1.2], semi-axes (1, 0.85, 0.7) R)",
           "lc = %g;" % a.radius]
    for i, p in enumerate(pts):
        out.append("Point(%d) = {%.9g, %.9g, %.9g, lc};" % (i + 1, p[0], p[1], p[2]))
    loops = []
    for fi, (i, j, k) in enumerate(faces):
        ids = []
        for a_, b_ in ((i, j), (j, k), (k, i)):
            key = (min(a_, b_), max(a_, b_))
            if key not in lines:
                lines[key] = len(lines) + 1
                out.append("Line(%d) = {%d, %d};" % (lines[key], key[0] + 1, key[1] + 1))
            ids.append(lines[key] if a_ < b_ else -lines[key])
        out.append("Curve Loop(%d) = {%d, %d, %d};" % (fi + 1, ids[0], ids[1], ids[2]))
        out.append("Plane Surface(%d) = {%d};" % (fi + 1, fi + 1))
        loops.append(fi + 1)
    out.append("Surface Loop(1) = {%s};" % ", ".join(str(x) for x in loops))
    out.append("Volume(1) = {1};")
    out.append('Physical Volume("grain") = {1};')
    out.append('Physical Surface("surface") = {%s};' % ", ".join(str(x) for x in loops))
    with open(a.out, "w") as f:
        f.write("\n".join(out) + "\n")
    z = [p[2] for p in pts]
    vol = 0.0
    for i, j, k in faces:
        p, q, r = pts[i], pts[j], pts[k]
        vol += (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) + p[2] * (q[0] * r[1] - q[1] * r[0])) / 6
    print("%s: %d points, %d faces; z from %.6g to %.6g m; volume %.6g m^3" % (a.out, len(pts), len(faces), min(z), max(z), vol))


if __name__ == "__main__":
    main()
