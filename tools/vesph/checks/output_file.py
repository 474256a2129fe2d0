#!/usr/bin/python3
"""Validate a vesph output (format "vesph-1"): the HDF5 file, its XDMF 3
companion and summary.json.

Usage
-----
    /usr/bin/python3 tools/check_output.py DIR_OR_H5 [--xdmf FILE] [--dtd FILE]

Arguments
---------
DIR_OR_H5   an output directory (every DIR/*.h5 is checked, each with the
            XDMF file of the same stem, and DIR/summary.json must exist and
            be valid JSON) or a single .h5 file (its <stem>.xdmf beside it is
            used; summary.json beside it is checked only if present).
--xdmf FILE XDMF file to check instead of <stem>.xdmf (only with one .h5).
--dtd FILE  DTD for the XDMF validation (default: xdmf3.dtd next to this
            script, i.e. tools/xdmf3.dtd).

What is checked
---------------
(a) HDF5: root attributes format == "vesph-1", dim (integer, 2 or 3),
    scene (string holding valid TOML; its "dimension" must equal dim),
    dx and h (float64 > 0), kernel (string); /frames holds >= 1 group named
    with 6 zero-padded digits, each with attributes time (float) and step
    (integer), times non-decreasing; every frame has id uint64 [N],
    kind uint8 [N] (values 0..3), position/velocity float64 [N,dim],
    density/mass/pressure float64 [N], optional extra_stress float64
    [N,3] (2D) / [N,6] (3D), extra_stress_zz float64 [N] (2D) and
    free_surface uint8 [N]; ids are unique and
    floating-point data are finite; /diagnostics has the float64 1-D
    columns time, dt, kinetic_energy, mass, max_speed,
    max_density_deviation, all of one length; /gauges, when present, holds
    one group per gauge with a type attribute and float64 1-D columns as
    long as its time column.
(b) XDMF: well-formed XML, and valid against the DTD, by running
        xmllint --noout --nonet --dtdvalid tools/xdmf3.dtd FILE
    (the harmless "failed to load external entity Xdmf.dtd" warning caused
    by the DOCTYPE line is ignored).
(c) XDMF <-> HDF5: every Format="HDF" DataItem ("file.h5:/path", file
    relative to the XDMF file) names an existing dataset whose shape equals
    Dimensions and whose dtype matches NumberType/Precision (XDMF defaults
    Float/4 when absent); every uniform Grid's Topology NumberOfElements
    equals the frame's N; each Time Value equals the frame's time attribute
    (relative tolerance 1e-12, so values must be written with ~15+
    significant digits); GeometryType is XY (2D) / XYZ (3D) and points to
    position; every frame appears in exactly one Grid, inside a Temporal
    collection.  One deliberate dtype exception: a uint64 dataset may be
    declared NumberType="Int" Precision="8" (reads exactly while values
    < 2^63, and ParaView 5.11 needs it: it clamps UInt/8 to 32 bits).
    ParaView-compatibility notes are printed as WARNINGs, not failures.

Units: none are converted; times are compared in the file's units (s).
Exit status: 0 when no problem was found, 1 otherwise (every problem is
listed), 2 for usage errors.
"""

import argparse
import glob
import json
import math
import os
import re
import subprocess
import sys
import tomllib
import xml.etree.ElementTree as ET

import numpy as np

from vesph import TOOLS
from vesph.output import as_str

DEFAULT_DTD = os.path.join(TOOLS, "xdmf3.dtd")

MANDATORY = ["id", "kind", "position", "velocity", "density", "mass", "pressure"]
OPTIONAL = ["extra_stress", "extra_stress_zz", "free_surface"]
DIAGNOSTICS = ["time", "dt", "kinetic_energy", "mass", "max_speed",
               "max_density_deviation"]
TIME_RTOL = 1e-12

# (NumberType, Precision) -> numpy (kind, itemsize)
XDMF_TYPES = {
    ("Char", 1): ("i", 1), ("UChar", 1): ("u", 1),
    ("Short", 2): ("i", 2), ("UShort", 2): ("u", 2),
    ("Int", 1): ("i", 1), ("Int", 2): ("i", 2), ("Int", 4): ("i", 4), ("Int", 8): ("i", 8),
    ("UInt", 1): ("u", 1), ("UInt", 2): ("u", 2), ("UInt", 4): ("u", 4), ("UInt", 8): ("u", 8),
    ("Float", 4): ("f", 4), ("Float", 8): ("f", 8),
}


class Report:
    """Collects what was checked, problems and (deduplicated) warnings."""

    def __init__(self):
        self.problems = []
        self.warnings = {}

    def info(self, msg):
        print(f"  checked: {msg}")

    def problem(self, msg):
        self.problems.append(msg)
        print(f"  PROBLEM: {msg}")

    def warn(self, key, msg):
        if key not in self.warnings:
            self.warnings[key] = [msg, 0]
        self.warnings[key][1] += 1


def is_str(v):
    """Whether an HDF5 attribute is a string (bytes, numpy bytes or str, or a scalar array of one)."""
    if isinstance(v, np.ndarray) and v.shape == ():
        v = v[()]
    return isinstance(v, (str, bytes, np.bytes_))


def is_int(v):
    return isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_))


def is_float64(v):
    return isinstance(v, (float, np.float64))


def dtype_name(dt):
    return np.dtype(dt).name


# --------------------------------------------------------------------- HDF5
def check_h5(path, rep):
    """Check the HDF5 file; returns a dict with dim and per-frame info, or
    None if the file could not be read at all."""
    import h5py

    print(f"[hdf5] {path}")
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        rep.problem(f"{path}: cannot open as HDF5 ({e})")
        return None
    info = {"dim": None, "frames": {}}
    with f:
        a = f.attrs
        # --- root attributes
        fmt = (as_str(a["format"]) if is_str(a["format"]) else a["format"]) if "format" in a else None
        if fmt is None:
            rep.problem("root attribute 'format' is missing")
        elif fmt != "vesph-1":
            rep.problem(f"root attribute format = {fmt!r}, expected 'vesph-1'")
        dim = a.get("dim")
        if dim is None:
            rep.problem("root attribute 'dim' is missing")
        elif not is_int(dim) or int(dim) not in (2, 3):
            rep.problem(f"root attribute dim = {dim!r} ({type(dim).__name__}); "
                        "expected integer 2 or 3")
        else:
            info["dim"] = int(dim)
        if "scene" not in a:
            rep.problem("root attribute 'scene' is missing")
        elif not is_str(a["scene"]):
            rep.problem("root attribute 'scene' is not a string")
        else:
            try:
                scene = tomllib.loads(as_str(a["scene"]))
                # `pressure` exists when the scene has a pressure closure (WCSPH equation of
                # state; ISPH later); a scene without one has no pressure field to write.
                info["has_pressure"] = ("equation_of_state" in scene.get("effects", {})
                                        or scene.get("solver", {}).get("scheme") == "isph")
                if info["dim"] is not None and "dimension" in scene \
                        and scene["dimension"] != info["dim"]:
                    rep.problem(f"scene dimension = {scene['dimension']} but dim = {info['dim']}")
            except tomllib.TOMLDecodeError as e:
                rep.problem(f"root attribute 'scene' is not valid TOML ({e})")
        for name in ("dx", "h"):
            if name not in a:
                rep.problem(f"root attribute '{name}' is missing")
            elif not is_float64(a[name]):
                rep.problem(f"root attribute {name} has type {type(a[name]).__name__}, "
                            "expected float64")
            elif not a[name] > 0:
                rep.problem(f"root attribute {name} = {a[name]!r} must be > 0")
        if "kernel" not in a:
            rep.problem("root attribute 'kernel' is missing")
        elif not is_str(a["kernel"]):
            rep.problem("root attribute 'kernel' is not a string")
        rep.info("root attributes format, dim, scene (TOML), dx, h, kernel")

        # --- frames
        dim = info["dim"] or 2
        if "frames" not in f or not isinstance(f["frames"], h5py.Group):
            rep.problem("group /frames is missing")
        else:
            names = sorted(f["frames"].keys())
            if not names:
                rep.problem("/frames holds no frame")
            last_t = -math.inf
            for k, name in enumerate(names):
                g = f["frames"][name]
                where = f"/frames/{name}"
                if not re.fullmatch(r"\d{6}", name):
                    rep.problem(f"{where}: frame name is not 6 zero-padded digits")
                elif int(name) != k:
                    rep.warn("frame-gap", f"frame names are not consecutive from 000000 "
                             f"(first gap at {name})")
                if not isinstance(g, h5py.Group):
                    rep.problem(f"{where} is not a group")
                    continue
                t = g.attrs.get("time")
                if t is None:
                    rep.problem(f"{where}: attribute 'time' is missing")
                elif not is_float64(t):
                    rep.problem(f"{where}: attribute time has type {type(t).__name__}, "
                                "expected float64")
                else:
                    if float(t) < last_t:
                        rep.problem(f"{where}: time {float(t)!r} is smaller than the "
                                    f"previous frame's {last_t!r}")
                    last_t = float(t)
                st = g.attrs.get("step")
                if st is None:
                    rep.problem(f"{where}: attribute 'step' is missing")
                elif not is_int(st):
                    rep.problem(f"{where}: attribute step has type {type(st).__name__}, "
                                "expected int64")
                N = None
                if "id" in g and isinstance(g["id"], h5py.Dataset) and g["id"].ndim == 1:
                    N = g["id"].shape[0]
                elif "kind" in g and isinstance(g["kind"], h5py.Dataset) and g["kind"].ndim >= 1:
                    N = g["kind"].shape[0]
                expect = {
                    "id": ("uint64", (N,)), "kind": ("uint8", (N,)),
                    "position": ("float64", (N, dim)), "velocity": ("float64", (N, dim)),
                    "density": ("float64", (N,)), "mass": ("float64", (N,)),
                    "pressure": ("float64", (N,)),
                    "extra_stress": ("float64", (N, 3 if dim == 2 else 6)),
                    "extra_stress_zz": ("float64", (N,)),  # 2D, models with tau_zz (XPP)
                    "free_surface": ("uint8", (N,)),
                }
                for ds in MANDATORY + OPTIONAL:
                    if ds not in g:
                        if ds in MANDATORY and not (ds == "pressure"
                                                    and not info.get("has_pressure", True)):
                            rep.problem(f"{where}/{ds}: missing")
                        continue
                    d = g[ds]
                    if not isinstance(d, h5py.Dataset):
                        rep.problem(f"{where}/{ds}: not a dataset")
                        continue
                    want_dt, want_shape = expect[ds]
                    if d.dtype != np.dtype(want_dt):
                        rep.problem(f"{where}/{ds}: dtype {dtype_name(d.dtype)}, expected {want_dt}")
                    if N is not None and d.shape != want_shape:
                        rep.problem(f"{where}/{ds}: shape {list(d.shape)}, expected "
                                    f"{list(want_shape)}")
                    if d.dtype.kind == "f" and d.size and not np.all(np.isfinite(d[...])):
                        rep.problem(f"{where}/{ds}: contains non-finite values (NaN/inf)")
                for ds in g:
                    if ds not in expect:
                        rep.warn(f"extra-{ds}", f"frames contain a dataset '{ds}' that is not "
                                 "part of vesph-1")
                if "kind" in g and g["kind"].dtype.kind in "iu" and g["kind"].size:
                    kv = np.unique(g["kind"][...])
                    bad = kv[kv > 3]
                    if bad.size:
                        rep.problem(f"{where}/kind: invalid values {bad.tolist()} (allowed 0..3)")
                if "id" in g and g["id"].ndim == 1 and g["id"].size:
                    ids = g["id"][...]
                    if np.unique(ids).size != ids.size:
                        rep.problem(f"{where}/id: ids are not unique")
                    info.setdefault("max_id", 0)
                    info["max_id"] = max(info["max_id"], int(ids.max()))
                info["frames"][name] = {"time": float(t) if t is not None else None, "N": N}
            rep.info(f"{len(names)} frame(s): attributes time/step, datasets "
                     + ", ".join(MANDATORY) + " (+ optional " + ", ".join(OPTIONAL)
                     + ") with dtypes and shapes [N] / [N,dim]")

        # --- diagnostics
        if "diagnostics" not in f or not isinstance(f["diagnostics"], h5py.Group):
            rep.problem("group /diagnostics is missing")
        else:
            lengths = set()
            for col in DIAGNOSTICS:
                if col not in f["diagnostics"]:
                    rep.problem(f"/diagnostics/{col}: missing")
                    continue
                d = f["diagnostics"][col]
                if not isinstance(d, h5py.Dataset) or d.ndim != 1:
                    rep.problem(f"/diagnostics/{col}: not a 1-D dataset")
                    continue
                if d.dtype != np.float64:
                    rep.problem(f"/diagnostics/{col}: dtype {dtype_name(d.dtype)}, expected float64")
                lengths.add(d.shape[0])
            if len(lengths) > 1:
                rep.problem(f"/diagnostics columns have different lengths {sorted(lengths)}")
            rep.info("/diagnostics columns " + ", ".join(DIAGNOSTICS))

        # --- gauges (optional: scenes with [[gauges]]): per gauge a group with a type
        # attribute and float64 1-D columns, "time" first, all as long as the time column
        if "gauges" in f:
            if not isinstance(f["gauges"], h5py.Group):
                rep.problem("/gauges is not a group")
            else:
                for name, g in f["gauges"].items():
                    where = f"/gauges/{name}"
                    if not isinstance(g, h5py.Group) or "time" not in g:
                        rep.problem(f"{where}: expected a group with a time column")
                        continue
                    if "type" not in g.attrs:
                        rep.problem(f"{where}: no type attribute")
                    n = g["time"].shape[0] if g["time"].ndim == 1 else -1
                    for col, d in g.items():
                        if not isinstance(d, h5py.Dataset) or d.ndim != 1 or d.dtype != np.float64:
                            rep.problem(f"{where}/{col}: expected a float64 1-D dataset")
                        elif d.shape[0] != n:
                            rep.problem(f"{where}/{col}: {d.shape[0]} rows, its time column {n}")
                rep.info(f"/gauges: {len(f['gauges'])} gauge(s)")
    return info


# --------------------------------------------------------------------- XDMF
def run_xmllint(xdmf, dtd, rep):
    try:
        p = subprocess.run(["xmllint", "--noout", "--nonet", "--dtdvalid", dtd, xdmf],
                           capture_output=True, text=True)
    except FileNotFoundError:
        rep.problem("xmllint not found (install libxml2-utils): DTD validation impossible")
        return
    lines = p.stderr.splitlines()
    kept, skip = [], 0
    for line in lines:
        if skip:
            skip -= 1
            continue
        if "failed to load external entity" in line and "Xdmf.dtd" in line:
            skip = 2          # libxml2 echoes the offending line and a caret
            continue
        kept.append(line)
    if p.returncode != 0:
        errors = [ln for ln in kept if "error" in ln]
        first = errors[0].split(": ", 1)[-1] if errors else "see output"
        rep.problem(f"xmllint --dtdvalid {os.path.relpath(dtd)} failed (exit {p.returncode}, "
                    f"{len(errors)} error line(s); first: {first}):")
        for line in kept[:40]:
            print(f"      {line}")
        if len(kept) > 40:
            print(f"      ... {len(kept) - 40} more line(s)")
    else:
        rep.info(f"XDMF is valid against {os.path.relpath(dtd)} (xmllint --dtdvalid)")


def parse_dims(text):
    try:
        dims = tuple(int(x) for x in text.split())
    except (AttributeError, ValueError):
        return None
    return dims if dims else None


def leaf_dataitems(elem):
    """Yield DataItems without DataItem children below elem."""
    for di in elem.iter("DataItem"):
        if di.find("DataItem") is None:
            yield di


def check_dataitem(di, where, xdmf_dir, h5cache, rep, main_h5, max_id):
    """Check one leaf DataItem; returns (h5 path, dataset path, shape) for HDF."""
    import h5py

    dims = parse_dims(di.get("Dimensions"))
    if dims is None:
        rep.problem(f"{where}: DataItem has no valid Dimensions ({di.get('Dimensions')!r})")
        return None
    fmt = di.get("Format", "XML")
    ntype = di.get("NumberType", di.get("DataType", "Float"))
    prec = di.get("Precision", "4")
    try:
        prec = int(prec)
    except ValueError:
        rep.problem(f"{where}: Precision {prec!r} is not an integer")
        return None
    if (ntype, prec) not in XDMF_TYPES:
        rep.problem(f"{where}: unsupported NumberType/Precision {ntype}/{prec}")
        return None
    if fmt == "XML":
        n_values = len((di.text or "").split())
        if n_values != int(np.prod(dims)):
            rep.problem(f"{where}: XML DataItem holds {n_values} values, Dimensions say "
                        f"{' '.join(map(str, dims))}")
        return None
    if fmt != "HDF":
        rep.warn(f"fmt-{fmt}", f"DataItem Format={fmt} is not checked against data")
        return None
    ref = (di.text or "").strip()
    if ":" not in ref:
        rep.problem(f"{where}: HDF DataItem text {ref!r} is not 'file.h5:/path'")
        return None
    fname, dpath = ref.split(":", 1)
    fpath = os.path.normpath(os.path.join(xdmf_dir, fname))
    if main_h5 and os.path.abspath(fpath) != os.path.abspath(main_h5):
        rep.warn(f"otherfile-{fname}", f"DataItems point to {fname}, not to the checked "
                 f"file {os.path.basename(main_h5)}")
    if fpath not in h5cache:
        try:
            h5cache[fpath] = h5py.File(fpath, "r")
        except OSError as e:
            h5cache[fpath] = None
            rep.problem(f"{where}: cannot open HDF5 file {fname!r} ({e})")
    f = h5cache[fpath]
    if f is None:
        return None
    if dpath not in f or not isinstance(f[dpath], h5py.Dataset):
        rep.problem(f"{where}: {fname}:{dpath} does not exist (or is not a dataset)")
        return None
    d = f[dpath]
    if tuple(d.shape) != dims:
        rep.problem(f"{where}: {dpath} has shape {list(d.shape)} but Dimensions = "
                    f"\"{di.get('Dimensions')}\"")
    kind, size = XDMF_TYPES[(ntype, prec)]
    if (d.dtype.kind, d.dtype.itemsize) != (kind, size):
        if d.dtype == np.uint64 and (ntype, prec) == ("Int", 8):
            if max_id is not None and max_id >= 2 ** 63:
                rep.problem(f"{where}: uint64 {dpath} declared Int/8 but holds values >= 2^63")
            else:
                rep.warn("u64-as-i64", "uint64 datasets declared NumberType=\"Int\" "
                         "Precision=\"8\" (accepted: exact below 2^63)")
        else:
            rep.problem(f"{where}: {dpath} is {dtype_name(d.dtype)} but the DataItem says "
                        f"NumberType=\"{ntype}\" Precision=\"{prec}\"")
    elif (ntype, prec) == ("UInt", 8):
        rep.warn("uint8-byte", "NumberType=\"UInt\" Precision=\"8\": ParaView 5.11 (Xdmf3 "
                 "and XDMF readers) reads it as 32-bit unsigned and clamps values >= 2^32 "
                 "to 4294967295; declare NumberType=\"Int\" Precision=\"8\" instead")
    return fpath, dpath, tuple(d.shape)


def check_xdmf(xdmf, dtd, h5info, main_h5, rep):
    print(f"[xdmf] {xdmf}")
    if not os.path.isfile(xdmf):
        rep.problem(f"XDMF file {xdmf} does not exist")
        return
    try:
        root = ET.parse(xdmf).getroot()
    except ET.ParseError as e:
        rep.problem(f"XDMF is not well-formed XML: {e}")
        return
    rep.info("XDMF is well-formed XML")
    run_xmllint(xdmf, dtd, rep)
    if root.tag != "Xdmf":
        rep.problem(f"root element is <{root.tag}>, expected <Xdmf>")
        return
    xdmf_dir = os.path.dirname(os.path.abspath(xdmf))
    dim = (h5info or {}).get("dim")
    frames = (h5info or {}).get("frames", {})
    max_id = (h5info or {}).get("max_id")
    h5cache = {}
    seen = {}
    n_items = 0

    def walk(grid, parents):
        nonlocal n_items
        gtype = grid.get("GridType", "Uniform")
        if gtype in ("Collection", "Tree"):
            for child in grid.findall("Grid"):
                walk(child, parents + [grid])
            return
        gname = grid.get("Name", "?")
        where = f"Grid {gname!r}"
        # which frame does this grid describe?
        frame_names = set()
        for di in leaf_dataitems(grid):
            m = re.search(r":/?frames/(\d{6})/", (di.text or "").strip())
            if m:
                frame_names.add(m.group(1))
        if len(frame_names) > 1:
            rep.problem(f"{where}: DataItems point to several frames {sorted(frame_names)}")
        frame = next(iter(frame_names)) if len(frame_names) == 1 else None
        if frame is None:
            m = re.search(r"(\d{6})$", gname)
            frame = m.group(1) if m else None
        fi = frames.get(frame)
        if fi is None:
            rep.problem(f"{where}: cannot tie it to a frame of the HDF5 file")
        else:
            seen.setdefault(frame, []).append(gname)
        if not any(p.get("GridType") == "Collection" and p.get("CollectionType") == "Temporal"
                   for p in parents) and len(frames) > 1:
            rep.problem(f"{where} is not inside a GridType=\"Collection\" "
                        "CollectionType=\"Temporal\" grid")
        N = fi["N"] if fi else None
        # Time
        tel = grid.find("Time")
        if tel is None:
            tel = next((p.find("Time") for p in reversed(parents) if p.find("Time") is not None),
                       None)
        if tel is None or tel.get("Value") is None:
            rep.problem(f"{where}: no <Time Value=...>")
        elif fi is not None and fi["time"] is not None:
            try:
                tv = float(tel.get("Value"))
                ft = fi["time"]
                if abs(tv - ft) > TIME_RTOL * max(abs(ft), abs(tv)):
                    rep.problem(f"{where}: Time Value {tel.get('Value')} != frame {frame} time "
                                f"{ft!r}")
            except ValueError:
                rep.problem(f"{where}: Time Value {tel.get('Value')!r} is not a number")
        # Topology
        topo = grid.find("Topology")
        if topo is None:
            rep.problem(f"{where}: no <Topology>")
        else:
            tt = topo.get("TopologyType", topo.get("Type"))
            if tt != "Polyvertex":
                rep.warn("topo", f"TopologyType={tt} (vesph writes Polyvertex)")
            ne = topo.get("NumberOfElements")
            if ne is None:
                rep.problem(f"{where}: Topology has no NumberOfElements")
            elif N is not None and ne.strip() != str(N):
                rep.problem(f"{where}: Topology NumberOfElements = {ne} but frame {frame} has "
                            f"N = {N}")
            if topo.get("NodesPerElement", "1") != "1":
                rep.problem(f"{where}: Polyvertex NodesPerElement = "
                            f"{topo.get('NodesPerElement')}, expected 1")
        # Geometry
        geo = grid.find("Geometry")
        if geo is None:
            rep.problem(f"{where}: no <Geometry>")
        else:
            gt = geo.get("GeometryType", geo.get("Type", "XYZ"))
            want = {2: "XY", 3: "XYZ"}.get(dim)
            if want and gt != want:
                rep.problem(f"{where}: GeometryType = {gt}, expected {want} for dim = {dim}")
            for di in leaf_dataitems(geo):
                if not (di.text or "").strip().endswith("/position"):
                    rep.problem(f"{where}: Geometry DataItem does not point to position")
        # all DataItems, with the attribute they belong to
        for owner in [geo, topo] + grid.findall("Attribute"):
            if owner is None:
                continue
            oname = owner.tag if owner.tag != "Attribute" else f"Attribute {owner.get('Name')!r}"
            for fdi in owner.iter("DataItem"):
                if fdi.get("ItemType") == "Function":
                    rep.warn("function", "ItemType=\"Function\" DataItems are skipped by "
                             "ParaView 5.11's Xdmf3 readers (only the legacy XDMF reader "
                             "evaluates them)")
            leaves = list(leaf_dataitems(owner))
            if owner.tag == "Attribute" and not leaves:
                rep.problem(f"{where}/{oname}: no DataItem")
            results = []
            for di in leaves:
                n_items += 1
                r = check_dataitem(di, f"{where}/{oname}", xdmf_dir, h5cache, rep, main_h5,
                                   max_id)
                if r:
                    results.append(r)
            if owner.tag == "Attribute" and N is not None:
                at = owner.get("AttributeType", "Scalar")
                top = owner.find("DataItem")
                dims = parse_dims(top.get("Dimensions")) if top is not None else None
                if dims:
                    if dims[0] != N:
                        rep.problem(f"{where}/{oname}: first dimension {dims[0]} != N = {N}")
                    ncomp = int(np.prod(dims[1:])) if len(dims) > 1 else 1
                    if at == "Scalar" and ncomp != 1:
                        rep.warn("scalar-multi", "Scalar attributes with several components "
                                 f"(e.g. {owner.get('Name')}) are flattened to N*k tuples by "
                                 "ParaView's legacy XDMF reader; use AttributeType=\"Matrix\"")
                    elif at == "Vector" and ncomp not in (2, 3):
                        rep.problem(f"{where}/{oname}: Vector with {ncomp} components")
                    elif at == "Vector" and ncomp == 2:
                        rep.warn("vector2", "2-component Vector attributes: ParaView 5.11's "
                                 "Xdmf3 readers load them as plain 2-component arrays (not "
                                 "usable as vectors by Glyph/Calculator); its legacy 'XDMF "
                                 "Reader' pads them to 3 components")
                    elif at == "Tensor6" and ncomp != 6:
                        rep.problem(f"{where}/{oname}: Tensor6 with {ncomp} components")
                    elif at == "Tensor" and ncomp != 9:
                        rep.problem(f"{where}/{oname}: Tensor with {ncomp} components")
        if fi is not None:
            names = {a.get("Name") for a in grid.findall("Attribute")}
            for want in ("velocity", "density", "pressure", "mass", "id", "kind"):
                if want not in names:
                    rep.warn(f"missing-attr-{want}", f"no Attribute named {want!r} in the XDMF")

    domains = root.findall("Domain")
    if not domains:
        rep.problem("no <Domain>")
    for dom in domains:
        grids = dom.findall("Grid")
        if not grids:
            rep.problem("Domain has no Grid")
        for g in grids:
            walk(g, [])
    for f in h5cache.values():
        if f is not None:
            f.close()
    for name in sorted(frames):
        if name not in seen:
            rep.problem(f"frame {name} of the HDF5 file has no Grid in the XDMF")
        elif len(seen[name]) > 1:
            rep.problem(f"frame {name} appears in {len(seen[name])} Grids: {seen[name]}")
    rep.info(f"{len(seen)} uniform grid(s) vs {len(frames)} HDF5 frame(s); {n_items} DataItem(s): "
             "dataset exists, shape == Dimensions, dtype == NumberType/Precision; "
             "NumberOfElements == N; Time == frame time")


def main(argv=None):
    ap = argparse.ArgumentParser(description="Validate a vesph-1 output (HDF5 + XDMF).")
    ap.add_argument("target", metavar="DIR_OR_H5")
    ap.add_argument("--xdmf", metavar="FILE", help="XDMF file (default <stem>.xdmf)")
    ap.add_argument("--dtd", metavar="FILE", default=DEFAULT_DTD,
                    help="DTD for xmllint (default tools/xdmf3.dtd)")
    a = ap.parse_args(argv)

    rep = Report()
    if os.path.isdir(a.target):
        h5files = sorted(glob.glob(os.path.join(a.target, "*.h5")))
        summary = os.path.join(a.target, "summary.json")
        summary_required = True
        if not h5files:
            rep.problem(f"no *.h5 file in {a.target}")
    elif os.path.isfile(a.target):
        h5files = [a.target]
        summary = os.path.join(os.path.dirname(os.path.abspath(a.target)), "summary.json")
        summary_required = False
    else:
        print(f"error: {a.target} does not exist", file=sys.stderr)
        return 2
    if a.xdmf and len(h5files) > 1:
        print("error: --xdmf needs a single .h5 file", file=sys.stderr)
        return 2
    if not os.path.isfile(a.dtd):
        print(f"error: DTD {a.dtd} not found", file=sys.stderr)
        return 2

    print("[summary]")
    if os.path.isfile(summary):
        try:
            with open(summary) as fh:
                json.load(fh)
            rep.info(f"{summary} is valid JSON")
        except (OSError, ValueError) as e:
            rep.problem(f"{summary} is not valid JSON ({e})")
    elif summary_required:
        rep.problem(f"{summary} is missing")
    else:
        print(f"  note: no {summary} (not required when a single .h5 is given)")

    for h5 in h5files:
        info = check_h5(h5, rep)
        xdmf = a.xdmf or os.path.splitext(h5)[0] + ".xdmf"
        check_xdmf(xdmf, a.dtd, info, h5, rep)

    for msg, count in rep.warnings.values():
        print(f"WARNING: {msg}" + (f"  [{count}x]" if count > 1 else ""))
    if rep.problems:
        print(f"RESULT: FAIL, {len(rep.problems)} problem(s):")
        for p in rep.problems:
            print(f"  - {p}")
        return 1
    print("RESULT: OK, no problems found")
    return 0


if __name__ == "__main__":
    sys.exit(main())
