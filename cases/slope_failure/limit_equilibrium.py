#!/usr/bin/python3
"""Limit-equilibrium factor of safety of the slope's weathered wedge sliding on its base plane.

Planar sliding of a rigid wedge of weight W (per metre of slope) on a plane of length L inclined at
beta, with cohesion c and friction angle phi (Mohr-Coulomb, no water pressure):

    FS = (c L + W cos(beta) tan(phi)) / (W sin(beta))

The geometry and the properties are read from slope.geo and case.json in this folder, so the two
stay in step. A strength reduction factor SRF divides c and tan(phi); the slope is at limit
equilibrium when SRF = FS (the shear strength reduction definition of the factor of safety).
Usage: limit_equilibrium.py [case.json]
"""
import json
import math
import os
import re
import sys

here = os.path.dirname(os.path.abspath(__file__))
case_path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "case.json")
geo = open(os.path.join(here, "slope.geo")).read()


def geo_value(name):
    m = re.search(r"\b%s = ([0-9.]+)( \* Pi / 180)?;" % name, geo)
    v = float(m.group(1))
    return v * math.pi / 180 if m.group(2) else v


H, toe, hd = geo_value("H"), geo_value("toe"), geo_value("hd")
face, weak = geo_value("face"), geo_value("weak")
with open(case_path) as f:
    case = json.load(f)
rho = case["materials"]["rock"]["density"]
g = abs(case["boundary"]["gravity"][1])
im = case["interface_materials"]["weathered_if"]
c, phi = im["c"], math.radians(im["phi_deg"])

xf = toe + H / math.tan(face)        # crest of the face
xd = toe + hd / math.tan(face)       # daylight point of the weak plane on the face
xw = xd + (H - hd) / math.tan(weak)  # end of the weak plane on the top surface
area = 0.5 * (H - hd) * (xw - xf)    # triangle (daylight point, crest, end of weak plane)
W = rho * g * area
L = math.hypot(xw - xd, H - hd)
FS = (c * L + W * math.cos(weak) * math.tan(phi)) / (W * math.sin(weak))
print("wedge area %.2f m^2, weight %.4g N/m, base length %.2f m, base angle %.1f deg" % (area, W, L, math.degrees(weak)))
print("c = %.4g Pa, phi = %.1f deg" % (c, math.degrees(phi)))
print("factor of safety (planar sliding, limit equilibrium): %.3f" % FS)
