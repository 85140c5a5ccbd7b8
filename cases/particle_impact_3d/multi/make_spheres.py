#!/usr/bin/python3
"""Writes spheres.geo: many rock spheres of random sizes at random, non-overlapping positions above
a plate, for cases/particle_impact_3d/multi/case.json.

    cases/particle_impact_3d/multi/make_spheres.py [--count N] [--rmin R] [--rmax R] [--width W]
                                                   [--gap G] [--seed S] [--out spheres.geo]

Radii are uniform in [rmin, rmax]; centres are drawn uniformly in a column of width W x W above
the plate (z = 0) and rejected when a sphere would come closer than `gap` to another one or to the
plate; the column grows upwards until all N spheres fit. Gmsh's OpenCASCADE kernel makes the
spheres; all of them form the region "particles" and their surfaces the node set "surface". The
points carry no size: the case caps the element size with mesh.element_size. Prints the count,
the total volume and the height of the pile.
"""
import argparse
import math
import random


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--count", type=int, default=200)
    ap.add_argument("--rmin", type=float, default=0.004)
    ap.add_argument("--rmax", type=float, default=0.008)
    ap.add_argument("--width", type=float, default=0.15)
    ap.add_argument("--gap", type=float, default=0.5e-3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default="spheres.geo")
    a = ap.parse_args()
    rnd = random.Random(a.seed)
    placed = []
    height = 4 * a.rmax
    tries = 0
    while len(placed) < a.count:
        r = rnd.uniform(a.rmin, a.rmax)
        c = (rnd.uniform(r - a.width / 2, a.width / 2 - r), rnd.uniform(r - a.width / 2, a.width / 2 - r),
             rnd.uniform(r + a.gap, height - r))
        if all(math.dist(c, q) > r + s + a.gap for q, s in placed):
            placed.append((c, r))
            tries = 0
        else:
            tries += 1
            if tries > 200:  # crowded: let the column grow
                height *= 1.1
                tries = 0
    out = ['// %d rock spheres written by make_spheres.py --count %d --rmin %g --rmax %g --width %g --gap %g --seed %d'
           % (a.count, a.count, a.rmin, a.rmax, a.width, a.gap, a.seed),
           'SetFactory("OpenCASCADE");',
           'Mesh.Optimize = 1;  // fewer slivers: a larger stable time step']
    for i, (c, r) in enumerate(placed):
        out.append("Sphere(%d) = {%.9g, %.9g, %.9g, %.9g};" % (i + 1, c[0], c[1], c[2], r))
    ids = ", ".join(str(i + 1) for i in range(len(placed)))
    out.append('Physical Volume("particles") = {%s};' % ids)
    out.append('Physical Surface("surface") = Boundary{ Volume{%s}; };' % ids)
    with open(a.out, "w") as f:
        f.write("\n".join(out) + "\n")
    vol = sum(4 / 3 * math.pi * r ** 3 for _, r in placed)
    top = max(c[2] + r for c, r in placed)
    print("%s: %d spheres, volume %.6g m^3, lowest bottom at z = %.4g m, top at z = %.4g m"
          % (a.out, len(placed), vol, min(c[2] - r for c, r in placed), top))


if __name__ == "__main__":
    main()
