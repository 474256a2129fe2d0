#!/usr/bin/python3
"""Measure a vesph drop-impact run (Fang et al. 2006 section 4): spread, height, volume and
fracture indicators of the drop at every frame, as CSV and PNG.

Usage
-----
    /usr/bin/python3 tools/drop_measure.py H5FILE [H5FILE ...] [--compare H5FILE ...]
        [--out-dir DIR] [--prefix NAME] [--no-png] [--link 1.5] [--min-cluster 2]
        [--min-fragment 0.01]
        [--contact 1.5] [--wall-y Y] [--until T]
        [--max-volume-error E] [--no-fracture | --expect-fracture] [--max-gap 2.5]
        [--crack-radius 3] [--max-crack 0.05] [--max-nn-gap G]
        [--time-offset T0] [--speed V] [--min-spread S] [--expect-retraction F]

The scene
---------
Read from the file (root attribute ``scene``): the drop is the fluid block with
shape = "disk" (2D) or "sphere" (3D): its diameter D and velocity; V = |velocity[1]| (the
vertical component; it must not be 0). The wall position y_w is the top (max[1]) of the
highest wall block lying below the drop (y = 0 in cases/drop_*.toml); --wall-y overrides it.
dx is the root attribute ``dx`` (else particles.spacing). Time is reported as t V/D.
--speed V replaces V and --time-offset T0 (s) is added to the file's times: a run that starts
the drop part-way through its fall (cases/drop_3d_*.toml: a drop in free fall without surface
tension does not deform) is reported on the clock of the release at speed V.

Per frame (fluid particles, kind 0)
-----------------------------------
- width: max x - min x of all fluid particle centres (m and /D): the spread of the drop. A
  lattice disk has width D (or D - 2 dx) at t = 0: centres, not the outer surface.
- bulk width: max x - min x of the largest cluster (below): the spread of the drop itself.
  Particles that the rim leaves behind on the wall as it retracts (or droplets flung off) keep
  the width of all fluid at the farthest point ever reached; the bulk width retracts with the
  drop.
- spread: twice the largest horizontal distance of a particle of the largest cluster from the
  drop's vertical axis (the block's centre; 2D |x - x_c|, 3D the distance in the x-z plane):
  the diameter of the drop's footprint in 3D, where the width along x alone would miss the
  spread along z.
- contact width: max x - min x of the fluid particles with y - y_w <= --contact dx (default
  1.5 dx: the first particle row on the wall sits at y_w + dx/2); 0 with fewer than 2 such
  particles; n_contact counts them.
- height: max y of the fluid - y_w (m and /D).
- volume: sum m_i/rho_i (2D: area in m^2, 3D: m^3), its relative error against the first
  frame of the file and against the disk pi D^2/4 (3D: pi D^3/6).
- interior density: the summation density rho~_i = sum_j m_j W(r_ij, h) (the scene's kernel
  and h, fluid and wall particles) of the interior fluid particles, those whose kernel support
  holds no open grid point (below: at least one support radius from the outside and from every
  void, with a grid spacing to spare); interior_density_rel_err = their mean rho~ / the same mean in the first frame - 1.
  It measures how much the particles have been compressed (> 0) or spread apart (< 0), and
  -interior_density_rel_err is the volume error this implies. Unlike sum m/rho it means
  something in ISPH, where rho stays rho0 by construction and sum m/rho cannot change.
- clusters: fluid particles closer than --link dx (default 1.5) are linked (cKDTree pairs,
  connected components); a component of fewer than --min-cluster (default 2) particles is
  "detached" (splashed-off single particles); clusters = number of components of at least
  --min-cluster particles; largest cluster fraction = its particles / all fluid particles.
- max NN gap: the largest nearest-neighbour distance over all fluid particles, / dx. It is the
  isolation of the loneliest particle: > link exactly when some particle is detached; a clean
  hole inside the drop does not raise it (the particles on its rim keep their neighbours).
- void gap: the diameter of the largest empty circle (sphere) not open to the outside, / dx.
  The distance d to the nearest fluid particle is sampled on a grid of spacing dx/2 (coarser
  if the grid would exceed 2e6 points) over the fluid's bounding box padded by 2 dx; grid
  points with d > r_open are "open", r_open = max(link/2, 0.525 sqrt(dim)) dx (0.75 dx in
  2D, 0.91 dx in 3D: above the half-diagonal of a lattice cell); open points connected
  (through open points, face neighbours) to the box border are the outside. void gap =
  2 max d over the other points. An intact lattice gives at most 2 r_open (1.41 inside a
  2D lattice, 1.73 in 3D); one missing particle gives 2, an interior hole of radius r about
  2r/dx. Accurate to about the grid spacing.
- void fraction: the area (3D: volume) of the enclosed open grid points / the first frame's
  volume: the total size of the interior voids less a rim of about r_open (0 for an intact
  lattice). sum m/rho does not see voids: the particles' densities stay near rho0.
- crack fraction: cracks open to the surface are part of the outside, so neither the void
  measures nor the clusters see them while the pieces hang together. The region not outside
  is closed (dilated, then eroded) with a ball of radius --crack-radius dx (default 3): the
  grid points the closing adds are the narrow openings of the outside (cracks, slots, gaps
  between particle columns up to about 2 R wide); their area (3D: volume) / the first
  frame's volume is the crack fraction. A smooth surface adds almost nothing; the staircase
  of a lattice disk gives about 0.5 % (D = 100 dx) to 2 % (D = 20 dx).
- fragments: clusters of at least --min-fragment (default 0.01) of the fluid particles. A
  smaller cluster is a droplet: a few particles flung off the rim (counted in clusters) do
  not make the drop fractured; the drop breaking into pieces does.
- fractured (a frame): fragments >= 2, or void gap > --max-gap (default 2.5), or crack
  fraction > --max-crack (default 0.05), or (only when given) max NN gap > --max-nn-gap.
  Detached particles alone do not make a fracture.

Checks (each optional; exit 1 when one fails)
--------------------------------------------
--max-volume-error E  every checked frame has |V/V_first - 1| <= E;
--no-fracture         no checked frame is fractured;
--expect-fracture     at least one checked frame is fractured;
--until T             only frames with t V/D <= T are measured and checked;
--min-spread S        the largest spread / D over the checked frames is at least S;
--expect-retraction F the spread falls after its maximum: the smallest spread of the later
                      frames is at most (1 - F) times the maximum (the viscoelastic drop's
                      retraction, Fang et al. 2006 Figs. 3-8).

Outputs
-------
<prefix>_drop.csv (one row per frame) and <prefix>_drop.png (panels width/D, height/D,
volume error %, clusters and detached, void / crack / outside-the-largest-cluster %, void and
NN gaps, against t V/D), in --out-dir (default: the directory of the file); prefix defaults
to the scene name. With several files
each gets its CSV (<label>_drop.csv) and one PNG overlays all runs, <prefix>_drop.png
with prefix defaulting to "compare". The label is the scene name; a name shared by several
runs gets the file's directory name appended (name_dir), and then _2, _3, ... if needed.
A summary table is printed for every run. --pictures T1,T2,... also writes
<prefix>_frames.png: the fluid particles of the frames nearest to those t V/D (a row per
time, a column per run; x / D from the drop's centre line, y / D above the wall; in 3D the
particles of the section |z - z_c| <= 0.6 dx through the drop's axis).

Exit status: 0 when all requested checks pass; 1 when a check fails or a file cannot be used
(missing, not HDF5, not a vesph output, no disk fluid block, no frames); 2 for usage errors.
A file still being written (locked by the writer) is opened without locking; an incomplete
last frame is skipped with a note.
"""

import argparse
import csv
import math
import os
import sys

import numpy as np

from vesph import kernels
from vesph import output as vesph_output
from vesph.output import Output, ToolError

PROG = "drop_measure"
MAX_GRID_POINTS = 2_000_000


class Drop(Output):
    """The scene geometry and frame list of one vesph drop-impact output (a run still writing
    it may be measured: the file is opened without locking, a half-written last frame skipped)."""

    def __init__(self, path, wall_y=None):
        self._wall_y = wall_y
        super().__init__(path, live=True, partial_last_frame=True)

    def _check_scene(self):
        """The disk block (D, centre, V) and the wall below it, from the scene."""
        path, wall_y = self.path, self._wall_y
        sc = self.scene
        blocks = sc.get("blocks", [])
        disks = [b for b in blocks if b.get("kind") == "fluid"
                 and b.get("shape") in ("disk", "sphere")]
        if not disks:
            raise ToolError(f"{path}: the scene has no disk fluid block ([[blocks]] kind = "
                            "\"fluid\", shape = \"disk\" or \"sphere\"): not a drop scene")
        if len(disks) > 1:
            self.notes.append(f"{len(disks)} disk fluid blocks: D and V from the first")
        b = disks[0]
        try:
            self.D = float(b["diameter"])
            self.centre = [float(c) for c in b["centre"]]
        except (KeyError, TypeError, ValueError):
            raise ToolError(f"{path}: the disk fluid block has no diameter/centre")
        vel = b.get("velocity", sc.get("initial", {}).get("velocity", [0.0] * self.dim))
        self.velocity = [float(v) for v in vel]
        self.V = abs(self.velocity[1])
        if not (self.D > 0):
            raise ToolError(f"{path}: the disk diameter is {self.D:g}, expected > 0")
        if not (self.V > 0):
            raise ToolError(f"{path}: the disk's vertical velocity velocity[1] is 0: no "
                            "impact velocity V for t V/D")
        self.area0 = (math.pi * self.D ** 2 / 4.0 if self.dim == 2
                      else math.pi * self.D ** 3 / 6.0)
        if wall_y is not None:
            self.wall_y = float(wall_y)
            self.wall_note = f"--wall-y {self.wall_y:g} m"
        else:
            bottom = self.centre[1] - 0.5 * self.D
            tops = [float(w["max"][1]) for w in blocks
                    if w.get("kind") == "wall" and "max" in w
                    and float(w["max"][1]) <= bottom + 1e-9 * self.D]
            if not tops:
                raise ToolError(f"{path}: no wall block below the drop (a [[blocks]] kind = "
                                "\"wall\" with max[1] below the disk); give --wall-y")
            self.wall_y = max(tops)
            self.wall_note = "top of the wall block below the drop"

    def read_fluid(self, k):
        """(positions [n, dim], mass [n], density [n]) of the fluid particles of frame k, and
        (positions, masses) of all particles (fluid and walls) for the summation density."""
        d = self.read_or_skip(k, ("kind", "position", "mass", "density"))
        if d is None:
            return None
        kind, pos, m, rho = d["kind"], d["position"], d["mass"], d["density"]
        fl = kind == 0
        if not np.any(fl):
            raise ToolError(f"{self.path}: frame {self.frames[k][0]} has no fluid particles (kind 0)")
        return pos[fl], m[fl], rho[fl], pos, m


# -------------------------------------------------------------------------- measures
def clusters(pos, link_dist, min_cluster, min_fragment=0.0):
    """(number of clusters of >= min_cluster particles, detached particles, largest size,
    fragments: clusters of at least min_fragment of all particles and >= min_cluster,
    mask of the particles in the largest cluster)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    n = len(pos)
    pairs = cKDTree(pos).query_pairs(link_dist, output_type="ndarray")
    a = coo_matrix((np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])),
                   shape=(n, n))
    _, labels = connected_components(a, directed=False)
    sizes = np.bincount(labels)
    big = sizes >= min_cluster
    fragment = big & (sizes >= min_fragment * n)
    largest = labels == int(np.argmax(sizes))
    return (int(np.count_nonzero(big)), int(sizes[~big].sum()), int(sizes.max()),
            int(np.count_nonzero(fragment)), largest)


def nearest_neighbour_distances(pos):
    """Each particle's distance to its nearest neighbour (None with < 2 particles)."""
    from scipy.spatial import cKDTree

    if len(pos) < 2:
        return None
    d, _ = cKDTree(pos).query(pos, k=2)
    return d[:, 1]


def max_nn_gap(pos):
    """Largest nearest-neighbour distance over the particles (nan with < 2 particles)."""
    d = nearest_neighbour_distances(pos)
    return float("nan") if d is None else float(d.max())


def open_radius(dim, link):
    """Grid points farther than this (in dx) from every particle are open: link/2, but above
    the half-diagonal sqrt(dim)/2 of a lattice cell (0.87 in 3D) so that an intact lattice
    has no open point inside."""
    return max(0.5 * link, 0.525 * math.sqrt(dim))


def open_grid(pos, dx, link, pad_dx=2.0):
    """The grid of the void gap (the module docstring), padded by pad_dx dx: dict with lo [dim],
    s (grid spacing), shape, d (distance to the nearest particle per grid point), open (farther
    than open_radius from every particle), outside (the open points connected to the border)
    and r_open [m]. grid_measures and void_origin.VoidTracker share it."""
    from scipy import ndimage
    from scipy.spatial import cKDTree

    dim = pos.shape[1]
    pad = pad_dx * dx
    lo = pos.min(axis=0) - pad
    hi = pos.max(axis=0) + pad
    s = 0.5 * dx
    npts = np.prod(np.floor((hi - lo) / s) + 1)
    if npts > MAX_GRID_POINTS:
        s *= (npts / MAX_GRID_POINTS) ** (1.0 / dim)
    axes = [lo[i] + s * np.arange(int(math.floor((hi[i] - lo[i]) / s)) + 1) for i in range(dim)]
    shape = tuple(len(a) for a in axes)
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    d, _ = cKDTree(pos).query(grid, k=1)
    d = d.reshape(shape)
    r_open = open_radius(dim, link) * dx
    open_ = d > r_open
    lab, _ = ndimage.label(open_)
    border = np.zeros(shape, dtype=bool)
    for ax in range(dim):
        idx = [slice(None)] * dim
        idx[ax] = 0
        border[tuple(idx)] = True
        idx[ax] = -1
        border[tuple(idx)] = True
    outside_labels = np.unique(lab[border & open_])
    outside = np.isin(lab, outside_labels[outside_labels > 0])
    return {"lo": lo, "s": s, "shape": shape, "d": d, "open": open_, "outside": outside,
            "r_open": r_open}


def grid_measures(pos, dx, link, crack_radius, cracks=True):
    """Void and crack measures on a grid (see the module docstring): dict with void_gap [m],
    void_area and crack_area [m^2, 3D: m^3], the grid spacing [m] and, per particle, the
    distance [m] from its grid point to the nearest open point (outside or void), and the
    open grid (`open_grid`). cracks=False leaves the crack area (nan) and the
    per-particle distance (None) out, the costly part; the grid is the same."""
    from scipy import ndimage

    g = open_grid(pos, dx, link, 2.0 + crack_radius)
    lo, s, shape, d, open_, outside = (g[k] for k in ("lo", "s", "shape", "d", "open", "outside"))
    dim = pos.shape[1]
    inside = ~outside
    inner = d[inside]
    enclosed = int(np.count_nonzero(open_ & inside))
    out = {"void_gap": 2.0 * float(inner.max()) if inner.size else 0.0,
           "void_area": enclosed * s ** dim, "crack_area": float("nan"), "grid": s,
           "particle_to_open": None, "open_grid": g}
    if not cracks:
        return out
    # closing of the inside by a ball of radius crack_radius dx (via distance transforms):
    # dilate (points within R of the inside), then erode (points farther than R from the
    # complement of the dilated set); what it adds are the narrow openings of the outside
    R = crack_radius * dx
    dilated = ndimage.distance_transform_edt(outside, sampling=s) <= R
    closed = ndimage.distance_transform_edt(dilated, sampling=s) > R
    crack = int(np.count_nonzero(closed & outside))
    to_open = ndimage.distance_transform_edt(~open_, sampling=s)
    cell = np.clip(np.rint((pos - lo) / s).astype(int), 0, np.array(shape) - 1)
    out["crack_area"] = crack * s ** dim
    out["particle_to_open"] = to_open[tuple(cell.T)]
    return out


def interior_density(drop, pos, pos_all, m_all, to_open, grid):
    """Mean summation density [kg/m^3] of the fluid particles whose kernel support holds no
    open grid point, and their count. to_open is sampled at the particle's nearest grid point
    (up to a grid spacing off): a particle counts when to_open >= the support radius + grid."""
    from scipy.spatial import cKDTree

    kernel = kernels.Kernel.for_output(drop)
    radius = kernel.support * drop.h
    inner = np.flatnonzero(to_open >= radius + grid)
    if inner.size == 0:
        return float("nan"), 0
    pairs = cKDTree(pos[inner]).sparse_distance_matrix(cKDTree(pos_all), radius,
                                                        output_type="coo_matrix")
    w = kernel.W(pairs.data / drop.h) / drop.h ** drop.dim
    # the pairs include each particle with itself (distance 0)
    rho = np.bincount(pairs.row, weights=w * m_all[pairs.col], minlength=inner.size)
    return float(np.mean(rho)), int(inner.size)


def measure(drop, a):
    """Rows (dicts) for the frames with t V/D <= a.until (all without --until)."""
    dx, D, V = drop.dx, drop.D, drop.V
    t0 = a.time_offset
    first = drop.read_fluid(0)
    if first is None:
        raise ToolError(f"{drop.path}: the first frame cannot be read")
    vol_first = float(np.sum(first[1] / first[2]))
    drop.vol_first, drop.t_first = vol_first, drop.frames[0][1]
    rows = []
    # --pictures: the frame nearest to each requested t V/D (one picture per time)
    times = np.array([(t + t0) * V / D for _, t in drop.frames])
    picture_frames = {int(np.argmin(np.abs(times - want))) for want in (a.pictures or [])}
    drop.pictures = {}
    for k, (nm, t) in enumerate(drop.frames):
        t = t + t0
        tvd = t * V / D
        if a.until is not None and tvd > a.until + 1e-9 * max(1.0, abs(a.until)):
            break
        got = first if k == 0 else drop.read_fluid(k)
        if got is None:
            break
        pos, m, rho, pos_all, m_all = got
        if k in picture_frames:
            drop.pictures[k] = (tvd, pos.copy())
        vol = float(np.sum(m / rho))
        x, y = pos[:, 0], pos[:, 1]
        h = y - drop.wall_y
        near = h <= a.contact * dx
        nc = int(np.count_nonzero(near))
        cw = float(x[near].max() - x[near].min()) if nc >= 2 else 0.0
        ncl, ndet, big, nfrag, in_largest = clusters(pos, a.link * dx, a.min_cluster, a.min_fragment)
        xb = x[in_largest]
        bulk = float(xb.max() - xb.min())
        across = [0] if drop.dim == 2 else [0, 2]  # the horizontal axes
        horizontal = pos[in_largest][:, across] - np.array(drop.centre)[across]
        spread = 2.0 * float(np.sqrt(np.max(np.sum(horizontal ** 2, axis=1))))
        nn = max_nn_gap(pos) / dx
        gm = grid_measures(pos, dx, a.link, a.crack_radius)
        vg = gm["void_gap"] / dx
        rho_in, n_in = interior_density(drop, pos, pos_all, m_all, gm["particle_to_open"], gm["grid"])
        if k == 0:
            drop.rho_interior_first = rho_in
        cf = gm["crack_area"] / vol_first
        width = float(x.max() - x.min())
        height = float(y.max() - drop.wall_y)
        frac = (nfrag >= 2 or vg > a.max_gap or cf > a.max_crack
                or (a.max_nn_gap is not None and nn > a.max_nn_gap))
        rows.append({
            "frame": nm, "time_s": t, "tV_D": tvd,
            "width_m": width, "width_D": width / D,
            "bulk_width_m": bulk, "bulk_width_D": bulk / D,
            "spread_m": spread, "spread_D": spread / D,
            "contact_width_m": cw, "contact_width_D": cw / D, "n_contact": nc,
            "height_m": height, "height_D": height / D,
            "volume": vol, "volume_rel_err_first": vol / vol_first - 1.0,
            "volume_rel_err_disk": vol / drop.area0 - 1.0,
            "interior_density_rel_err": rho_in / drop.rho_interior_first - 1.0,
            "n_interior": n_in,
            "n_fluid": len(x), "clusters": ncl, "fragments": nfrag, "detached": ndet,
            "largest_cluster_fraction": big / len(x),
            "max_nn_gap_dx": nn, "void_gap_dx": vg,
            "void_fraction": gm["void_area"] / vol_first, "crack_fraction": cf,
            "fractured": int(frac), "grid": gm["grid"],
        })
    return rows


COLUMNS = [  # (key, csv header; {vol} is replaced by volume_m2 / volume_m3)
    ("frame", "frame"), ("time_s", "time_s"), ("tV_D", "tV_over_D"),
    ("width_m", "width_m"), ("width_D", "width_over_D"),
    ("bulk_width_m", "bulk_width_m"), ("bulk_width_D", "bulk_width_over_D"),
    ("spread_m", "spread_m"), ("spread_D", "spread_over_D"),
    ("contact_width_m", "contact_width_m"), ("contact_width_D", "contact_width_over_D"),
    ("n_contact", "n_contact"), ("height_m", "height_m"), ("height_D", "height_over_D"),
    ("volume", "{vol}"), ("volume_rel_err_first", "volume_rel_err_first"),
    ("volume_rel_err_disk", "volume_rel_err_disk"), ("n_fluid", "n_fluid"),
    ("clusters", "clusters"), ("fragments", "fragments"), ("detached", "detached"),
    ("largest_cluster_fraction", "largest_cluster_fraction"),
    ("max_nn_gap_dx", "max_nn_gap_over_dx"), ("void_gap_dx", "void_gap_over_dx"),
    ("void_fraction", "void_fraction"), ("crack_fraction", "crack_fraction"),
    ("fractured", "fractured"),
    ("interior_density_rel_err", "interior_density_rel_err"), ("n_interior", "n_interior"),
]


def write_csv(path, rows, dim):
    vol = "volume_m2" if dim == 2 else "volume_m3"
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([h.format(vol=vol) for _, h in COLUMNS])
        for r in rows:
            w.writerow([repr(float(r[k])) if isinstance(r[k], (float, np.floating)) else r[k]
                        for k, _ in COLUMNS])


def plot(png, runs, a, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(2, 3, figsize=(15, 8.4), sharex=True)
    axs = axs.ravel()
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (label, rows) in enumerate(runs):
        c = colors[i % len(colors)]
        t = [r["tV_D"] for r in rows]
        col = lambda k: [r[k] for r in rows]  # noqa: E731
        axs[0].plot(t, col("width_D"), "-", color=c, label=f"{label}: all fluid")
        axs[0].plot(t, col("bulk_width_D"), ":", color=c, label=f"{label}: largest cluster")
        axs[0].plot(t, col("contact_width_D"), "--", color=c, label=f"{label}: contact")
        if a.dim == 3:
            axs[0].plot(t, col("spread_D"), "-.", color=c, label=f"{label}: spread (x-z)")
        axs[1].plot(t, col("height_D"), "-", color=c, label=label)
        axs[2].plot(t, [100 * v for v in col("volume_rel_err_first")], "-", color=c,
                    label=f"{label}: vs first frame")
        axs[2].plot(t, [-100 * v for v in col("interior_density_rel_err")], "--", color=c,
                    label=f"{label}: from the interior summation density")
        axs[2].plot(t, [100 * v for v in col("volume_rel_err_disk")], ":", color=c,
                    label=f"{label}: vs " + ("pi D^2/4" if a.dim == 2 else "pi D^3/6"))
        axs[3].plot(t, col("clusters"), "o-", ms=3, color=c, label=f"{label}: clusters")
        axs[3].plot(t, col("detached"), "s--", ms=3, color=c, label=f"{label}: detached")
        axs[4].plot(t, [100 * v for v in col("void_fraction")], "-", color=c,
                    label=f"{label}: voids")
        axs[4].plot(t, [100 * v for v in col("crack_fraction")], "--", color=c,
                    label=f"{label}: cracks")
        axs[4].plot(t, [100 * (1 - v) for v in col("largest_cluster_fraction")], ":",
                    color=c, label=f"{label}: outside the largest cluster")
        axs[5].plot(t, col("void_gap_dx"), "-", color=c, label=f"{label}: void gap")
        axs[5].plot(t, col("max_nn_gap_dx"), "--", color=c, label=f"{label}: max NN gap")
    axs[5].axhline(a.max_gap, color="k", lw=0.8, ls=":", label=f"--max-gap {a.max_gap:g}")
    axs[4].axhline(100 * a.max_crack, color="k", lw=0.8, ls=":",
                   label=f"--max-crack {a.max_crack:g} ({100 * a.max_crack:g} %)")
    labels = [("width / D", "spread: width / D"), ("height / D", "height / D"),
              ("[%]", "volume (area) error"),
              ("count", "clusters (>= %d particles), detached particles" % a.min_cluster),
              ("% of the drop", "voids, cracks (/ first volume), outside the largest cluster"),
              ("gap / dx", "void gap, max nearest-neighbour gap")]
    for ax, (yl, tt) in zip(axs, labels):
        ax.set_ylabel(yl)
        ax.set_title(tt, fontsize="medium")
        ax.grid(alpha=0.3)
        ax.legend(fontsize="x-small")
    for ax in axs[3:]:
        ax.set_xlabel("t V / D")
    from matplotlib.ticker import MaxNLocator
    axs[3].yaxis.set_major_locator(MaxNLocator(integer=True))
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)


# ------------------------------------------------------------------------------ report
def plot_pictures(png, runs, a):
    """Particle pictures: one row per requested t V/D, one column per run; coordinates in D
    from the disk's centre line (x) and the wall (y)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = [(lab, d, sorted(d.pictures.values(), key=lambda v: v[0])) for lab, d in runs]
    nrow = max(len(p) for _, _, p in shown)
    xs = [(pos[:, 0] - d.centre[0]) / d.D for _, d, p in shown for _, pos in p]
    ys = [(pos[:, 1] - d.wall_y) / d.D for _, d, p in shown for _, pos in p]
    xmax = max(float(np.max(np.abs(x))) for x in xs) + 0.05
    ymax = max(float(np.max(y)) for y in ys) + 0.05
    width = 2 * xmax
    col_w = min(7.0, 1.6 * width)
    row_h = max(0.9, col_w * (ymax + 0.1) / width + 0.4)
    fig, axs = plt.subplots(nrow, len(shown), figsize=(col_w * len(shown), row_h * nrow),
                            squeeze=False)
    for c, (lab, d, pics) in enumerate(shown):
        # marker area about one particle at the figure's scale (points^2)
        size = max(0.2, (72.0 * col_w * d.dx / (d.D * width)) ** 2 * 0.6)
        for r in range(nrow):
            ax = axs[r][c]
            if r >= len(pics):
                ax.axis("off")
                continue
            tvd, pos = pics[r]
            if d.dim == 3:  # the section through the drop's axis
                pos = pos[np.abs(pos[:, 2] - d.centre[2]) <= 0.6 * d.dx]
            ax.scatter((pos[:, 0] - d.centre[0]) / d.D, (pos[:, 1] - d.wall_y) / d.D, s=size,
                       c="tab:blue", linewidths=0)
            ax.axhline(0.0, color="0.4", lw=0.8)
            ax.set_xlim(-xmax, xmax)
            ax.set_ylim(-0.05, ymax)
            ax.set_aspect("equal")
            ax.set_title(f"{lab}, t V/D = {tvd:.3g}", fontsize=9)
            ax.tick_params(labelsize=7)
    fig.supxlabel("x / D from the drop's centre line;\ny / D above the wall", fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def summarize(drop, rows, a, p):
    p(f"== {drop.name}: {drop.path}")
    for n in drop.notes:
        p("note: " + n)
    p(f"   {drop.dim}D, D = {drop.D:g} m, V = {drop.V:g} m/s ("
      + ("--speed" if a.speed is not None else "velocity[1] of the disk block")
      + (f"; times + {a.time_offset:g} s" if a.time_offset else "") + "), "
      f"D/V = {drop.D / drop.V:g} s, dx = {drop.dx:g} m (D/dx = {drop.D / drop.dx:g}), "
      f"wall y_w = {drop.wall_y:g} m ({drop.wall_note})")
    p(f"   first-frame volume {drop.vol_first:.6g} {'m^2' if drop.dim == 2 else 'm^3'} at "
      f"t = {drop.t_first:g} s; disk {drop.area0:.6g} (first/disk - 1 = "
      f"{100 * (drop.vol_first / drop.area0 - 1):+.3f} %)")
    if not rows:
        p("   no frame within --until")
        return
    p(f"   frames measured: {len(rows)} of {len(drop.frames)}, t V/D = {rows[0]['tV_D']:.4g}"
      f" ... {rows[-1]['tV_D']:.4g}" + (f" (--until {a.until:g})" if a.until is not None else ""))
    step = max(1, math.ceil(len(rows) / 16))
    show = sorted(set(range(0, len(rows), step)) | {len(rows) - 1})
    p(f"   {'tV/D':>6} {'width/D':>8} {'bulk/D':>7} {'spread/D':>8} {'contact/D':>9} {'height/D':>8} {'dV_first%':>9} "
      f"{'dV_disk%':>8} {'clusters':>8} {'detached':>8} {'largest':>7} {'NN gap':>7} "
      f"{'void':>6} {'void%':>6} {'crack%':>6} {'frac':>4}")
    for j in show:
        r = rows[j]
        p(f"   {r['tV_D']:6.3f} {r['width_D']:8.4f} {r['bulk_width_D']:7.4f} {r['spread_D']:8.4f} {r['contact_width_D']:9.4f} "
          f"{r['height_D']:8.4f} {100 * r['volume_rel_err_first']:9.3f} "
          f"{100 * r['volume_rel_err_disk']:8.3f} {r['clusters']:8d} {r['detached']:8d} "
          f"{r['largest_cluster_fraction']:7.4f} {r['max_nn_gap_dx']:7.3f} "
          f"{r['void_gap_dx']:6.2f} {100 * r['void_fraction']:6.2f} "
          f"{100 * r['crack_fraction']:6.2f} "
          f"{'yes' if r['fractured'] else 'no':>4}")
    if step > 1:
        p(f"   (every {step} frames and the last; all frames in the CSV)")
    contact = [r for r in rows if r["n_contact"] > 0]
    jw = int(np.argmax([r["width_D"] for r in rows]))
    p("   first wall contact: " + (f"t V/D = {contact[0]['tV_D']:.4g}" if contact else "none")
      + f"; max width/D {rows[jw]['width_D']:.4g} at t V/D = {rows[jw]['tV_D']:.4g}; "
      f"last height/D {rows[-1]['height_D']:.4g}")
    js, smin = spread_extremes(rows)
    p(f"   max spread/D {rows[js]['spread_D']:.4g} at t V/D = {rows[js]['tV_D']:.4g}; "
      + (f"smallest after it {smin['spread_D']:.4g} at t V/D = {smin['tV_D']:.4g} "
         f"(retraction {100 * (1 - smin['spread_D'] / rows[js]['spread_D']):.3g} %)"
         if smin is not None else "no later frame"))
    ve = max(abs(r["volume_rel_err_first"]) for r in rows)
    vd = max(abs(r["volume_rel_err_disk"]) for r in rows)
    p(f"   max |volume error|: {100 * ve:.4g} % vs the first frame, {100 * vd:.4g} % vs the disk")
    di = [r["interior_density_rel_err"] for r in rows if r["n_interior"] > 0]
    if di:
        p(f"   interior summation density vs the first frame: {100 * min(di):+.3g} % ... "
          f"{100 * max(di):+.3g} % (mean over the {rows[-1]['n_interior']} interior particles "
          "of the last frame; the volume error this implies has the opposite sign)")
    frac = [r for r in rows if r["fractured"]]
    p(f"   max clusters {max(r['clusters'] for r in rows)}, max detached "
      f"{max(r['detached'] for r in rows)}, min largest cluster "
      f"{min(r['largest_cluster_fraction'] for r in rows):.4f}, max NN gap "
      f"{max(r['max_nn_gap_dx'] for r in rows):.3g} dx, max void gap "
      f"{max(r['void_gap_dx'] for r in rows):.3g} dx, max void fraction "
      f"{100 * max(r['void_fraction'] for r in rows):.3g} %, max crack fraction "
      f"{100 * max(r['crack_fraction'] for r in rows):.3g} %; fractured frames: {len(frac)}"
      + (f" (first at t V/D = {frac[0]['tV_D']:.4g}: {', '.join(why_fractured(frac[0], a))})"
         if frac else ""))


def spread_extremes(rows):
    """(index of the largest spread, the row of the smallest spread after it or None)."""
    js = int(np.argmax([r["spread_D"] for r in rows]))
    later = rows[js + 1:]
    return js, (min(later, key=lambda r: r["spread_D"]) if later else None)


def why_fractured(r, a):
    """The criteria a fractured row meets, as text."""
    why = []
    if r["fragments"] >= 2:
        why.append(f"{r['fragments']} fragments")
    if r["void_gap_dx"] > a.max_gap:
        why.append(f"void gap {r['void_gap_dx']:.3g} dx")
    if r["crack_fraction"] > a.max_crack:
        why.append(f"crack fraction {100 * r['crack_fraction']:.3g} %")
    if a.max_nn_gap is not None and r["max_nn_gap_dx"] > a.max_nn_gap:
        why.append(f"NN gap {r['max_nn_gap_dx']:.3g} dx")
    return why


def checks(drop, rows, a, p):
    """Print the requested checks; return True when all pass."""
    ok = True
    if not rows:
        if requested_checks(a):
            p("   FAIL: no frame to check")
            return False
        return True
    if a.max_volume_error is not None:
        worst = max(rows, key=lambda r: abs(r["volume_rel_err_first"]))
        e = abs(worst["volume_rel_err_first"])
        good = e <= a.max_volume_error
        ok &= good
        p(f"   check volume error vs the first frame: max {100 * e:.4g} % at t V/D = "
          f"{worst['tV_D']:.4g} (limit {100 * a.max_volume_error:g} %): "
          + ("PASS" if good else "FAIL"))
    frac = [r for r in rows if r["fractured"]]
    crit = (f"fragments (>= {100 * a.min_fragment:g} % of the particles) >= 2 or void gap > {a.max_gap:g} dx or crack fraction > "
            f"{100 * a.max_crack:g} %") + (
        f" or NN gap > {a.max_nn_gap:g} dx" if a.max_nn_gap is not None else "")
    if a.no_fracture:
        good = not frac
        ok &= good
        if good:
            p(f"   check no fracture ({crit}): PASS")
        else:
            r = frac[0]
            why = why_fractured(r, a)
            p(f"   check no fracture ({crit}): FAIL: {len(frac)} fractured frame(s), first "
              f"at t V/D = {r['tV_D']:.4g} (frame {r['frame']}: {', '.join(why)})")
    if a.min_spread is not None or a.expect_retraction is not None:
        js, smin = spread_extremes(rows)
        top = rows[js]["spread_D"]
    if a.min_spread is not None:
        good = top >= a.min_spread
        ok &= good
        p(f"   check max spread/D {top:.4g} (t V/D = {rows[js]['tV_D']:.4g}) >= {a.min_spread:g}: "
          + ("PASS" if good else "FAIL"))
    if a.expect_retraction is not None:
        good = smin is not None and smin["spread_D"] <= (1 - a.expect_retraction) * top
        ok &= good
        p(f"   check retraction: the spread falls by at least {100 * a.expect_retraction:g} % "
          f"after its maximum {top:.4g} D: "
          + (f"smallest later {smin['spread_D']:.4g} D at t V/D = {smin['tV_D']:.4g}: "
             if smin is not None else "no later frame: ")
          + ("PASS" if good else "FAIL"))
    if a.expect_fracture:
        good = bool(frac)
        ok &= good
        p(f"   check fracture expected ({crit}): "
          + (f"PASS (first at t V/D = {frac[0]['tV_D']:.4g})" if good else
             "FAIL: no fractured frame"))
    return ok


# -------------------------------------------------------------------------------- main
def run_labels(drops):
    """Labels (and file-name stems) of the runs: the scene name; a name shared by several
    runs gets the name of the file's directory appended (name_dir), then _2, _3, ..."""
    names = [d.name for d in drops]
    labels = []
    for d in drops:
        lab = d.name
        if names.count(d.name) > 1:
            parent = os.path.basename(os.path.dirname(os.path.abspath(d.path)))
            lab = f"{d.name}_{parent}" if parent else d.name
        labels.append(lab)
    seen, out = {}, []
    for lab in labels:
        k = seen.get(lab, 0)
        seen[lab] = k + 1
        out.append(lab if k == 0 else f"{lab}_{k + 1}")
    return out


def run(a, out=sys.stdout):
    p = lambda *s: print(*s, file=out)  # noqa: E731
    files = list(a.h5files) + list(a.compare or [])
    if not files:
        raise ToolError("give at least one H5FILE", 2)
    drops, results = [], []
    try:
        for path in files:
            drops.append(Drop(path, a.wall_y))
            if a.speed is not None:
                drops[-1].V = a.speed
        a.dim = drops[0].dim
        all_ok = True
        for d in drops:
            rows = measure(d, a)
            summarize(d, rows, a, p)
            all_ok &= checks(d, rows, a, p)
            results.append((d, rows))
    finally:
        for d in drops:
            d.close()

    labels = run_labels([d for d, _ in results])
    single = len(results) == 1
    written = []
    for (d, rows), lab in zip(results, labels):
        od = a.out_dir if a.out_dir is not None else os.path.dirname(os.path.abspath(d.path))
        os.makedirs(od, exist_ok=True)
        pre = (a.prefix or lab) if single else lab
        fn = os.path.join(od, pre + "_drop.csv")
        write_csv(fn, rows, d.dim)
        written.append(fn)
    if not a.no_png:
        d0 = results[0][0]
        od = a.out_dir if a.out_dir is not None else os.path.dirname(os.path.abspath(d0.path))
        pre = (a.prefix or labels[0]) if single else (a.prefix or "compare")
        png = os.path.join(od, pre + "_drop.png")
        title = ("drop impact: " + ", ".join(labels)
                 + f"  (link {a.link:g} dx, contact {a.contact:g} dx)")
        plot(png, [(lab, rows) for (_, rows), lab in zip(results, labels)], a, title)
        written.append(png)
    if a.pictures:
        d0 = results[0][0]
        od = a.out_dir if a.out_dir is not None else os.path.dirname(os.path.abspath(d0.path))
        pre = (a.prefix or labels[0]) if single else (a.prefix or "compare")
        png = os.path.join(od, pre + "_frames.png")
        plot_pictures(png, [(lab, d) for (d, _), lab in zip(results, labels)], a)
        written.append(png)
    for w in written:
        p(f"wrote {w}")
    if requested_checks(a):
        p("RESULT: " + ("PASS" if all_ok else "FAIL"))
    return 0 if all_ok else 1


def requested_checks(a):
    return (a.max_volume_error is not None or a.no_fracture or a.expect_fracture
            or a.min_spread is not None or a.expect_retraction is not None)


picture_times = vesph_output.nonnegative_list("numbers t V/D")


def main(argv=None):
    ap = argparse.ArgumentParser(
        prog="drop_measure.py",
        description="Spread, height, volume and fracture indicators of a vesph drop-impact "
                    "run (Fang et al. 2006 section 4) against t V/D, as CSV and PNG; several "
                    "files are overlaid in one PNG.")
    ap.add_argument("h5files", nargs="*", metavar="H5FILE", help="vesph output file(s) (.h5)")
    ap.add_argument("--compare", nargs="+", metavar="H5FILE",
                    help="more runs to overlay (same as further positional files)")
    ap.add_argument("--out-dir", metavar="DIR",
                    help="directory for the CSV and PNG (default: that of the (first) file)")
    ap.add_argument("--prefix", metavar="NAME",
                    help="file name prefix (default: the scene name; 'compare' for the PNG "
                         "of several runs)")
    ap.add_argument("--no-png", action="store_true", help="write the CSV only")
    ap.add_argument("--pictures", metavar="T1,T2,...", type=picture_times,
                    help="also write PREFIX_frames.png: the fluid particles of the frames "
                         "nearest to these t V/D, one row per time, one column per run")
    ap.add_argument("--link", type=float, default=1.5, metavar="L",
                    help="particles closer than L dx are linked into a cluster (default 1.5)")
    ap.add_argument("--min-cluster", type=int, default=2, metavar="N",
                    help="smaller components are 'detached' particles (default 2)")
    ap.add_argument("--min-fragment", type=float, default=0.01, metavar="F",
                    help="clusters of at least this fraction of the fluid particles are "
                         "fragments; two fragments make a frame fractured (default 0.01)")
    ap.add_argument("--contact", type=float, default=1.5, metavar="C",
                    help="contact width: particles within C dx of the wall (default 1.5)")
    ap.add_argument("--wall-y", type=float, metavar="Y",
                    help="wall position [m] (default: top of the wall block below the drop)")
    ap.add_argument("--until", type=float, metavar="T",
                    help="only frames with t V/D <= T")
    ap.add_argument("--max-volume-error", type=float, metavar="E",
                    help="check: |V/V_first - 1| <= E at every frame (e.g. 0.01)")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--no-fracture", action="store_true",
                   help="check: no frame is fractured")
    g.add_argument("--expect-fracture", action="store_true",
                   help="check: some frame is fractured")
    ap.add_argument("--max-gap", type=float, default=2.5, metavar="G",
                    help="a void gap above G dx counts as a fracture (default 2.5)")
    ap.add_argument("--crack-radius", type=float, default=3.0, metavar="R",
                    help="cracks: openings of the outside closed by a ball of radius R dx "
                         "(default 3)")
    ap.add_argument("--max-crack", type=float, default=0.05, metavar="F",
                    help="a crack fraction above F counts as a fracture (default 0.05)")
    ap.add_argument("--max-nn-gap", type=float, metavar="G",
                    help="also count a max nearest-neighbour gap above G dx as a fracture "
                         "(off by default: it is raised by detached particles)")
    ap.add_argument("--time-offset", type=float, default=0.0, metavar="T0",
                    help="added to the file's times [s]: the run started T0 after the release "
                         "(default 0)")
    ap.add_argument("--speed", type=float, metavar="V",
                    help="the release speed V [m/s] for t V/D (default |velocity[1]| of the "
                         "drop block)")
    ap.add_argument("--min-spread", type=float, metavar="S",
                    help="check: the largest spread / D is at least S")
    ap.add_argument("--expect-retraction", type=float, metavar="F",
                    help="check: after its maximum the spread falls by at least the fraction F")
    a = ap.parse_args(argv)
    if not math.isfinite(a.time_offset):
        ap.error(f"--time-offset must be a finite number, got {a.time_offset:g}")
    if a.speed is not None and not (math.isfinite(a.speed) and a.speed > 0):
        ap.error(f"--speed must be a positive number, got {a.speed:g}")
    if a.expect_retraction is not None and not (0 < a.expect_retraction < 1):
        ap.error(f"--expect-retraction must be in (0, 1), got {a.expect_retraction:g}")
    if a.min_spread is not None and not (a.min_spread > 0):
        ap.error(f"--min-spread must be positive, got {a.min_spread:g}")
    for nm, v, lo in (("--link", a.link, 0), ("--contact", a.contact, 0),
                      ("--max-gap", a.max_gap, 0), ("--crack-radius", a.crack_radius, 0),
                      ("--max-crack", a.max_crack, 0)):
        if not (math.isfinite(v) and v > lo):
            ap.error(f"{nm} must be a positive number, got {v:g}")
    if a.min_cluster < 1:
        ap.error(f"--min-cluster must be >= 1, got {a.min_cluster}")
    if a.max_volume_error is not None and not (a.max_volume_error >= 0):
        ap.error(f"--max-volume-error must be >= 0, got {a.max_volume_error:g}")
    if not a.h5files and not a.compare:
        ap.error("give at least one H5FILE")
    return vesph_output.run_reporting_errors(PROG, run, a)


if __name__ == "__main__":
    sys.exit(main())
