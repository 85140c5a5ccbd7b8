#!/usr/bin/python3
"""Limit-equilibrium factor of safety of the slope's weathered wedge sliding on its base plane.

Planar sliding of a rigid wedge of weight W (per metre of slope) on a plane of length L inclined at
beta, with cohesion c and friction angle phi (Mohr-Coulomb, no water pressure):

    FS = (c L + W cos(beta) tan(phi)) / (W sin(beta))

The same with a dry vertical tension crack from the top surface down to the base plane at x_c
(Hoek & Bray, Rock Slope Engineering, planar failure with a tension crack in the upper surface):
only the part of the wedge in front of the crack slides, on the part of the base in front of it;
the crack carries nothing. The smallest FS over x_c is the critical tension crack.

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


def geo_value(geo, name):
    m = re.search(r"\b%s = ([0-9.]+)( \* Pi / 180)?;" % name, geo)
    v = float(m.group(1))
    return v * math.pi / 180 if m.group(2) else v


def factors(case_path=os.path.join(here, "case.json")):
    """Geometry, properties and factors of safety (dict)."""
    geo = open(os.path.join(here, "slope.geo")).read()
    H, toe, hd = geo_value(geo, "H"), geo_value(geo, "toe"), geo_value(geo, "hd")
    face, weak = geo_value(geo, "face"), geo_value(geo, "weak")
    with open(case_path) as f:
        case = json.load(f)
    rho = case["materials"]["rock"]["density"]
    g = abs(case["boundary"]["gravity"][1])
    im = case["interface_materials"]["weathered_if"]
    c, phi = im["c"], math.radians(im["phi_deg"])

    xf = toe + H / math.tan(face)        # crest of the face
    xd = toe + hd / math.tan(face)       # daylight point of the weak plane on the face
    xw = xd + (H - hd) / math.tan(weak)  # end of the weak plane on the top surface

    def fs_front_of(xc):
        """FS of the part of the wedge in front of a vertical crack at xc (xf <= xc <= xw)."""
        yb = hd + (xc - xd) * math.tan(weak)  # where the crack meets the base plane
        P = [(xd, hd), (xf, H), (xc, H), (xc, yb)]
        area = 0.5 * abs(sum(P[i][0] * P[(i + 1) % 4][1] - P[(i + 1) % 4][0] * P[i][1] for i in range(4)))
        W = rho * g * area
        L = math.hypot(xc - xd, yb - hd)
        return (c * L + W * math.cos(weak) * math.tan(phi)) / (W * math.sin(weak)), area, W, L

    FS, area, W, L = fs_front_of(xw)
    n = 2000
    crit = min((fs_front_of(xf + (xw - xf) * k / n)[0], xf + (xw - xf) * k / n) for k in range(1, n))
    return {"H": H, "beta_deg": math.degrees(weak), "face_deg": math.degrees(face), "xf": xf, "xd": xd, "xw": xw,
            "area": area, "weight": W, "base_length": L, "c": c, "phi_deg": math.degrees(phi),
            "FS": FS, "FS_tension_crack": crit[0], "x_tension_crack": crit[1]}


def main():
    r = factors(sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "case.json"))
    print("wedge area %.2f m^2, weight %.4g N/m, base length %.2f m, base angle %.1f deg"
          % (r["area"], r["weight"], r["base_length"], r["beta_deg"]))
    print("c = %.4g Pa, phi = %.1f deg" % (r["c"], r["phi_deg"]))
    print("factor of safety (planar sliding, limit equilibrium): %.3f" % r["FS"])
    print("with the critical dry vertical tension crack at x = %.2f m (%.2f m behind the crest): %.3f"
          % (r["x_tension_crack"], r["x_tension_crack"] - r["xf"], r["FS_tension_crack"]))


if __name__ == "__main__":
    main()
