#!/usr/bin/python3
"""Brazilian disc: the computed strength against the disc's size in characteristic lengths (issue 23).

A cohesive material's splitting strength depends on the disc diameter D measured in its
characteristic length l_ch = E G_c / f_t^2 (the length of the zone where the crack softens): a
small disc carries more than f_t, and the strength falls towards f_t as D / l_ch grows (the
cohesive size effect of the Brazilian test). The shipped case has D / l_ch = 2.6. Dividing the
fracture energies by k (the same mesh, platens and rate) moves the same disc to D / l_ch = 2.6 k.
At the case's 0.1 m/s the disc is not loaded quasi-statically (cases/brazilian_disc/README.md,
"The loading rate"), and smaller energies also soften faster, so these runs show size and rate
together: a trend, not the static size effect.

    perf/brazil_size_effect.py DIR [--k 1,2,4,10] [--png FILE] [--json FILE]

reads DIR/<label>.json of perf/brazil_scatter.py for every k (label `case` for k = 1, the shipped
case; `g_over_<k>` for the others, run with
`perf/brazil_scatter.py --sizes 0.003:7 --label g_over_<k> --set interface_materials.rock_if.Gnc=75/k
--set interface_materials.rock_if.Gsc=1500/k --out DIR`), prints the mean and standard deviation
of the strength error over the meshes for each D / l_ch, fits error = a + b l_ch / D by least
squares over the means (a straight line: the points bend down at large sizes, so its intercept a
is not the large-size limit), and draws the figure.
"""
import argparse
import json
import os
import sys

E, FT, GNC, D = 33e9, 8e6, 75.0, 0.1  # the shipped case (cases/brazilian_disc/case.json)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir")
    ap.add_argument("--k", default="1,2,4,10")
    ap.add_argument("--size", type=float, default=0.003, help="nominal element size of the runs (m)")
    ap.add_argument("--png")
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = []
    for k in [float(x) for x in a.k.split(",")]:
        label = "case" if k == 1 else f"g_over_{k:g}"
        path = os.path.join(a.dir, label + ".json")
        if not os.path.exists(path):
            print(f"brazil_size_effect: {path} is missing", file=sys.stderr)
            return 2
        d = json.load(open(path))
        st = next((s for s in d["statistics"] if abs(s["nominal_size_m"] - a.size) < 1e-9), None)
        if not st or st["error"]["n"] == 0:
            print(f"brazil_size_effect: {path} has no runs at h = {a.size}", file=sys.stderr)
            return 2
        lch = E * GNC / k / FT**2
        rows.append({"k": k, "D_over_lch": D / lch, "lch_over_D": lch / D, "meshes": st["error"]["n"],
                     "error_mean": st["error"]["mean"], "error_std": st["error"]["std"],
                     "first_failure_error_mean": st["first_failure_error"]["mean"],
                     "split_offset_mean_m": st["split_offset_m"]["mean"]})
    xs = [r["lch_over_D"] for r in rows]
    ys = [r["error_mean"] for r in rows]
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    a0 = my - b * mx
    print("D/l_ch   l_ch/D  meshes  strength error (mean +- std)  first failure  split offset")
    for r in rows:
        print(f"{r['D_over_lch']:6.2f}  {r['lch_over_D']:6.3f}  {r['meshes']:6d}  "
              f"{100 * r['error_mean']:+6.2f} % +- {100 * r['error_std']:4.2f} %          "
              f"{100 * r['first_failure_error_mean']:+6.2f} %      {1e3 * r['split_offset_mean_m']:.1f} mm")
    print(f"fit: error = {100 * a0:+.2f} % + {100 * b:.2f} % x l_ch / D  (a straight line through the means)")
    out = {"rows": rows, "fit": {"limit": a0, "slope": b}, "E": E, "ft": FT, "Gnc": GNC, "D": D}
    if a.json:
        json.dump(out, open(a.json, "w"), indent=1)
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        ax.errorbar(xs, [100 * y for y in ys], yerr=[100 * r["error_std"] for r in rows], fmt="o", capsize=4,
                    label="mean +- std over 7 meshes (R/17)")
        t = [0, max(xs) * 1.05]
        ax.plot(t, [100 * (a0 + b * x) for x in t], "--", label=f"fit {100 * a0:+.1f} % + {100 * b:.1f} % l_ch/D")
        ax.axhline(0, color="k", lw=0.8)
        for r in rows:
            ax.annotate(f"D = {r['D_over_lch']:.1f} l_ch", (r["lch_over_D"], 100 * r["error_mean"]),
                        textcoords="offset points", xytext=(6, -12), fontsize=8)
        ax.set_xlabel("l_ch / D  (l_ch = E G_nc / f_t^2)")
        ax.set_ylabel("strength 2 P / (pi D t) against f_t (%)")
        ax.set_title("Brazilian disc at 0.1 m/s: fracture energies / k (size and rate together)", fontsize=10)
        ax.set_xlim(left=0)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
