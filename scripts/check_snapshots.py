#!/usr/bin/env python3
"""Check an fdem snapshot pair: DIR/snapshots.h5 and DIR/snapshots.xdmf.

Every DataItem in the XDMF must name an existing dataset of the HDF5 file with the stated
dimensions and a matching number type; topologies, geometries and attributes must agree with each
other (element and node counts, 3 components for vectors, 6 for Tensor6). Prints a summary
(frames, nodes, elements, interfaces, max damage per frame).

Usage: check_snapshots.py DIR
Exit status: 0 if consistent, 1 on any mismatch, 2 if the files cannot be read.
"""
import os
import sys
import xml.etree.ElementTree as ET

try:
    import h5py
except ImportError:  # pragma: no cover
    sys.stderr.write("check_snapshots.py needs h5py (apt install python3-h5py or pip install h5py)\n")
    sys.exit(2)


class Checker:
    def __init__(self, h5, h5name, xdmf_dir):
        self.h5 = h5
        self.h5name = h5name
        self.xdmf_dir = xdmf_dir
        self.errors = []

    def error(self, msg):
        self.errors.append(msg)

    def data_item(self, item, where):
        """Checks one DataItem; returns (dims tuple, dataset) or (None, None)."""
        fmt = item.get("Format", "XML")
        dims_s = item.get("Dimensions")
        if dims_s is None:
            self.error(f"{where}: DataItem without Dimensions")
            return None, None
        try:
            dims = tuple(int(v) for v in dims_s.split())
        except ValueError:
            self.error(f"{where}: bad Dimensions '{dims_s}'")
            return None, None
        if fmt != "HDF":
            self.error(f"{where}: DataItem Format '{fmt}' (expected HDF)")
            return dims, None
        text = (item.text or "").strip()
        if ":" not in text:
            self.error(f"{where}: DataItem '{text}' is not FILE:/PATH")
            return dims, None
        fname, path = text.split(":", 1)
        if os.path.normpath(os.path.join(self.xdmf_dir, fname)) != os.path.normpath(self.h5name):
            self.error(f"{where}: DataItem refers to '{fname}', not snapshots.h5")
            return dims, None
        if path not in self.h5:
            self.error(f"{where}: dataset '{path}' does not exist in {os.path.basename(self.h5name)}")
            return dims, None
        ds = self.h5[path]
        if not isinstance(ds, h5py.Dataset):
            self.error(f"{where}: '{path}' is not a dataset")
            return dims, None
        if tuple(ds.shape) != dims:
            self.error(f"{where}: '{path}' has shape {tuple(ds.shape)}, XDMF says {dims}")
        ntype = item.get("NumberType", "Float")
        prec = int(item.get("Precision", "4"))
        kind = ds.dtype.kind
        if ntype in ("Int", "UInt") and kind not in "iu":
            self.error(f"{where}: '{path}' is {ds.dtype}, XDMF says {ntype}")
        if ntype == "Float" and kind != "f":
            self.error(f"{where}: '{path}' is {ds.dtype}, XDMF says Float")
        if ds.dtype.itemsize != prec:
            self.error(f"{where}: '{path}' has {ds.dtype.itemsize}-byte values, XDMF says Precision {prec}")
        return dims, ds

    def uniform_grid(self, grid, where):
        """Checks one uniform grid; returns dict with counts and the damage dataset."""
        name = grid.get("Name", "?")
        where = f"{where}/{name}"
        info = {"name": name, "nodes": None, "cells": None, "damage": None}
        topo = grid.find("Topology")
        geom = grid.find("Geometry")
        if topo is None or geom is None:
            self.error(f"{where}: grid without Topology or Geometry")
            return info
        ttype = topo.get("TopologyType", "")
        nel = int(topo.get("NumberOfElements", "-1"))
        npe_default = {"Triangle": 3, "Tetrahedron": 4, "Polyline": 2}.get(ttype)
        npe = int(topo.get("NodesPerElement", npe_default if npe_default is not None else -1))
        titem = topo.find("DataItem")
        if titem is None:
            self.error(f"{where}: Topology without DataItem")
            return info
        tdims, tds = self.data_item(titem, where + "/Topology")
        if tdims is not None and tdims != (nel, npe):
            self.error(f"{where}: Topology has NumberOfElements={nel}, NodesPerElement={npe} "
                       f"but DataItem Dimensions {tdims}")
        if npe_default is not None and npe != npe_default and ttype != "Polyline":
            self.error(f"{where}: {ttype} with NodesPerElement={npe}")
        info["cells"] = nel
        gtype = geom.get("GeometryType", "XYZ")
        gitem = geom.find("DataItem")
        if gitem is None:
            self.error(f"{where}: Geometry without DataItem")
            return info
        gdims, _ = self.data_item(gitem, where + "/Geometry")
        if gtype == "XYZ" and gdims is not None:
            if len(gdims) != 2 or gdims[1] != 3:
                self.error(f"{where}: XYZ geometry with Dimensions {gdims}")
            info["nodes"] = gdims[0]
        elif gtype == "XY" and gdims is not None:
            info["nodes"] = gdims[0]
        if tds is not None and info["nodes"] is not None and tds.size > 0:
            lo, hi = int(tds[()].min()), int(tds[()].max())
            if lo < 0 or hi >= info["nodes"]:
                self.error(f"{where}: connectivity uses node ids {lo}..{hi}, "
                           f"geometry has {info['nodes']} nodes")
        for attr in grid.findall("Attribute"):
            aname = attr.get("Name", "?")
            aw = f"{where}/{aname}"
            aitem = attr.find("DataItem")
            if aitem is None:
                self.error(f"{aw}: Attribute without DataItem")
                continue
            adims, ads = self.data_item(aitem, aw)
            if adims is None:
                continue
            center = attr.get("Center", "Node")
            want = info["nodes"] if center == "Node" else info["cells"] if center == "Cell" else None
            if want is not None and adims[0] != want:
                self.error(f"{aw}: {center} attribute with {adims[0]} values, grid has {want}")
            atype = attr.get("AttributeType", "Scalar")
            ncomp = {"Scalar": 1, "Vector": 3, "Tensor6": 6, "Tensor": 9}.get(atype)
            have = 1 if len(adims) == 1 else adims[1]
            if ncomp is not None and have != ncomp:
                self.error(f"{aw}: {atype} attribute with {have} components")
            if aname == "damage":
                info["damage"] = ads
        return info


def main(argv):
    if len(argv) != 2:
        sys.stderr.write(__doc__)
        return 2
    d = argv[1]
    h5name = os.path.join(d, "snapshots.h5")
    xname = os.path.join(d, "snapshots.xdmf")
    for p in (h5name, xname):
        if not os.path.isfile(p):
            print(f"error: {p} does not exist")
            return 2
    try:
        root = ET.parse(xname).getroot()
    except ET.ParseError as e:
        print(f"error: {xname} is not valid XML: {e}")
        return 1
    try:
        h5 = h5py.File(h5name, "r")
    except OSError as e:
        print(f"error: cannot open {h5name}: {e}")
        return 2

    with h5:
        c = Checker(h5, h5name, d)
        mesh = h5.get("/mesh")
        if mesh is None:
            c.error("snapshots.h5 has no /mesh group")
            nn = ne = ni = None
        else:
            nn = mesh["reference_coordinates"].shape[0] if "reference_coordinates" in mesh else None
            ne = mesh["elements"].shape[0] if "elements" in mesh else None
            ni = mesh["interfaces"].shape[0] if "interfaces" in mesh else None
            for name in ("elements", "region", "interfaces", "reference_coordinates"):
                if name not in mesh:
                    c.error(f"snapshots.h5: /mesh/{name} missing")

        domain = root.find("Domain")
        temporal = None if domain is None else domain.find("Grid")
        if temporal is None or temporal.get("CollectionType") != "Temporal":
            c.error("snapshots.xdmf: Domain has no temporal collection grid")
            frames = []
        else:
            frames = temporal.findall("Grid")

        rows = []
        xdmf_groups = set()
        for k, fr in enumerate(frames):
            fname = fr.get("Name", f"frame{k}")
            where = f"frame {k} ({fname})"
            t_el = fr.find("Time")
            t = float(t_el.get("Value")) if t_el is not None else None
            if t is None:
                c.error(f"{where}: no Time")
            if fr.get("GridType") == "Collection":
                grids = fr.findall("Grid")
            else:
                grids = [fr]
            infos = [c.uniform_grid(g, where) for g in grids]
            names = [i["name"] for i in infos]
            if "bulk" not in names:
                c.error(f"{where}: no 'bulk' grid")
            if ni and "interfaces" not in names:
                c.error(f"{where}: {ni} interfaces in the mesh but no 'interfaces' grid")
            for info in infos:
                if info["name"] == "bulk":
                    if nn is not None and info["nodes"] is not None and info["nodes"] != nn:
                        c.error(f"{where}: bulk has {info['nodes']} nodes, mesh has {nn}")
                    if ne is not None and info["cells"] != ne:
                        c.error(f"{where}: bulk has {info['cells']} cells, mesh has {ne}")
                if info["name"] == "interfaces" and ni is not None and info["cells"] != ni:
                    c.error(f"{where}: interfaces grid has {info['cells']} cells, mesh has {ni}")
            # Time agrees with the step group's attribute.
            grp = fname if fname in h5 else None
            if grp is not None:
                xdmf_groups.add(grp)
                ht = h5[grp].attrs.get("time")
                if ht is not None and t is not None and float(ht) != t:
                    c.error(f"{where}: XDMF time {t!r} but /{grp} has time {float(ht)!r}")
            dmg = None
            for info in infos:
                if info["damage"] is not None:
                    arr = info["damage"][()]
                    dmg = float(arr.max()) if arr.size else None
            step = int(h5[grp].attrs["step"]) if grp is not None and "step" in h5[grp].attrs else None
            rows.append((k, step, t, dmg))

        h5_steps = sorted(n for n in h5 if n.startswith("step_"))
        extra = [n for n in h5_steps if n not in xdmf_groups]

        print(f"{d}: {len(frames)} frames, {nn} nodes, {ne} elements, {ni} interfaces")
        print(f"{'frame':>6} {'step':>10} {'time':>14} {'max damage':>11}")
        for k, step, t, dmg in rows:
            ts = f"{t:14.6g}" if t is not None else f"{'-':>14}"
            ds = f"{dmg:11.4f}" if dmg is not None else f"{'-':>11}"
            ss = f"{step:10d}" if step is not None else f"{'-':>10}"
            print(f"{k:6d} {ss} {ts} {ds}")
        if extra:
            # A run killed between writing a frame and rewriting the XDMF leaves one such group.
            print(f"note: {len(extra)} step group(s) in snapshots.h5 not listed in the XDMF: "
                  + ", ".join(extra[:5]) + (" ..." if len(extra) > 5 else ""))
        if c.errors:
            for e in c.errors:
                print("MISMATCH: " + e)
            print(f"{len(c.errors)} mismatch(es)")
            return 1
        print("OK")
        return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
