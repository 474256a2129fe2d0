#!/usr/bin/python3
"""Open a vesph XDMF file with ParaView's readers and print what ParaView
actually sees: reader, time steps, and for every time step the number of
points, the point bounds and each point-data array with its VTK type,
number of components and per-component value range.

Usage (headless; no display or X server needed):
    pvpython tools/paraview_check.py FILE.xdmf [--reader xdmf3s|xdmf3t|legacy|all]
                                               [--json OUT.json]
    (/usr/bin/python3 works too on Debian, where ParaView's Python modules
    are installed system-wide; pvpython --force-offscreen-rendering also.)

Arguments
---------
FILE.xdmf   XDMF 3 file written by vesph (the .h5 it references must be
            where the XDMF says, relative to the XDMF file).
--reader    xdmf3s: "Xdmf3ReaderS" (default), xdmf3t: "Xdmf3ReaderT",
            legacy: "XDMFReader" (ParaView's XDMF 2 reader), all: each of
            them in turn.
--json OUT  also write the results (of the first reader) as JSON:
            {"reader", "timesteps", "steps": [{"time", "points", "bounds",
            "arrays": {name: {"components", "type", "range",
            "component_ranges"}}}]}.

Units: values are printed as stored (vesph writes SI: m, s, kg, Pa);
nothing is converted.  Exit status 0 when the file was read and every time
step has points, 1 otherwise.
"""

import argparse
import json
import os
import sys

READERS = {"xdmf3s": "Xdmf3ReaderS", "xdmf3t": "Xdmf3ReaderT", "legacy": "XDMFReader"}


def leaves(data):
    """Leaf datasets of a (possibly composite) VTK data object."""
    if data is None:
        return []
    if data.IsA("vtkCompositeDataSet"):
        out = []
        it = data.NewIterator()
        it.InitTraversal()
        while not it.IsDoneWithTraversal():
            out.append(it.GetCurrentDataObject())
            it.GoToNextItem()
        return out
    return [data]


def describe_step(data):
    blocks = [b for b in leaves(data) if b is not None and b.IsA("vtkDataSet")]
    npts = sum(b.GetNumberOfPoints() for b in blocks)
    info = {"points": npts, "blocks": len(blocks), "bounds": None, "arrays": {}}
    if blocks and npts:
        bounds = [float("inf"), -float("inf")] * 3
        for b in blocks:
            if b.GetNumberOfPoints() == 0:
                continue
            bb = b.GetBounds()
            for k in range(3):
                bounds[2 * k] = min(bounds[2 * k], bb[2 * k])
                bounds[2 * k + 1] = max(bounds[2 * k + 1], bb[2 * k + 1])
        info["bounds"] = bounds
    for b in blocks:
        pd = b.GetPointData()
        for i in range(pd.GetNumberOfArrays()):
            a = pd.GetAbstractArray(i)
            if a is None:
                continue
            name = a.GetName()
            nc = a.GetNumberOfComponents()
            entry = info["arrays"].setdefault(name, {
                "components": nc, "type": a.GetClassName(),
                "tuples": 0, "range": None, "component_ranges": None})
            entry["tuples"] += a.GetNumberOfTuples()
            if hasattr(a, "GetRange") and a.GetNumberOfTuples():
                cr = [list(a.GetRange(c)) for c in range(nc)]
                if entry["component_ranges"] is None:
                    entry["component_ranges"] = cr
                else:
                    entry["component_ranges"] = [
                        [min(o[0], n[0]), max(o[1], n[1])]
                        for o, n in zip(entry["component_ranges"], cr)]
                entry["range"] = [min(r[0] for r in entry["component_ranges"]),
                                  max(r[1] for r in entry["component_ranges"])]
    return info


def read_with(reader_name, path):
    import paraview.simple as pvs
    from paraview import servermanager as sm

    ctor = getattr(pvs, reader_name)
    if reader_name == "XDMFReader":
        r = ctor(FileNames=[path])
    else:
        r = ctor(FileName=[path])
    tv = r.TimestepValues
    try:
        times = [float(x) for x in tv]
    except TypeError:            # a single time step comes back as a number
        times = [] if tv is None else [float(tv)]
    steps = []
    for t in (times or [None]):
        if t is None:
            r.UpdatePipeline()
        else:
            r.UpdatePipeline(t)
        info = describe_step(sm.Fetch(r))
        info["time"] = t
        steps.append(info)
    pvs.Delete(r)
    return {"reader": reader_name, "file": path, "timesteps": times, "steps": steps}


def fmt(v):
    return f"{v:.6g}"


def print_result(res):
    print(f"== reader {res['reader']}  file {res['file']}")
    print(f"   {len(res['timesteps'])} time step(s): "
          + ", ".join(fmt(t) for t in res["timesteps"]))
    for st in res["steps"]:
        b = st["bounds"]
        bs = ("[" + ", ".join(f"{fmt(b[2 * k])}..{fmt(b[2 * k + 1])}" for k in range(3)) + "]"
              if b else "-")
        t = "-" if st["time"] is None else fmt(st["time"])
        print(f"   t = {t}: {st['points']} points in {st['blocks']} block(s), bounds {bs}")
        for name, a in sorted(st["arrays"].items()):
            cr = a["component_ranges"]
            rng = ("  ranges " + " ".join(f"[{fmt(lo)}, {fmt(hi)}]" for lo, hi in cr)) if cr else ""
            print(f"      {name:<14} {a['components']} component(s)  {a['type']:<22}"
                  f" {a['tuples']} tuples{rng}")


def main(argv=None):
    ap = argparse.ArgumentParser(description="Inspect a vesph XDMF file with ParaView.")
    ap.add_argument("xdmf", metavar="FILE.xdmf")
    ap.add_argument("--reader", choices=list(READERS) + ["all"], default="xdmf3s")
    ap.add_argument("--json", metavar="OUT.json")
    a = ap.parse_args(argv)
    path = os.path.abspath(a.xdmf)   # Xdmf3 readers mis-resolve bare relative names
    if not os.path.isfile(path):
        print(f"error: {a.xdmf} does not exist", file=sys.stderr)
        return 1
    names = list(READERS.values()) if a.reader == "all" else [READERS[a.reader]]
    ok = True
    results = []
    for rn in names:
        res = read_with(rn, path)
        results.append(res)
        print_result(res)
        if not res["steps"] or any(st["points"] == 0 for st in res["steps"]):
            print(f"   PROBLEM: {rn} produced a time step without points")
            ok = False
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(results[0], fh, indent=1)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
