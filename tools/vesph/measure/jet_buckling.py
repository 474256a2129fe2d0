#!/usr/bin/python3
"""Measure a vesph jet-buckling run (3D; Cruickshank & Munson 1981): a round viscous jet from
a circular nozzle (an [inflow] buffer with `radius`) falling onto a plate. Per frame the
buckling indicator (the lateral offset of the jet's axis from the nozzle axis), its direction,
the pile height and the void measures; over the run the buckling onset time and the coiling
frequency; CSV and PNG.

Usage
-----
    tools/vesph-post jet_buckling_measure H5FILE [--out-dir DIR] [--prefix NAME] [--no-png]
        [--threshold 0.25] [--pile-factor 2] [--band 1] [--trace 1] [--plate Y]
        [--pictures T1,T2,...] [--no-voids]
        [--expect-buckling | --expect-no-buckling] [--max-void-gap G] [--max-opened-gap G]

The scene
---------
Read from the file (root attribute ``scene``): the nozzle is the [inflow] with `radius` R
(D = 2R), its axis through the centre of the buffer box's cross-section along `direction`
(a coordinate axis: the flow direction, "down"), its exit the buffer's face the direction
points to (the inlet plane); U = `mean_velocity`. The plate is the wall block facing the
nozzle: of the wall blocks lying beyond the inlet along the direction, the face nearest to
it (the top, max[1], of the highest one for a jet falling along -y); --plate gives its
coordinate instead. H = the distance from the inlet to the plate. Heights are measured from
the plate towards the nozzle; "lateral" is the plane normal to the axis. Time is reported
as t U/D.

Per frame (fluid particles, kind 0)
-----------------------------------
The fluid between the plate and the nozzle is cut into slabs one dx thick normal to the axis.
Each slab's cross-section A = sum(m/rho)/dx and its mass-weighted centroid in the lateral
plane; its *offset* is the centroid's distance from the nozzle axis.

- pile height: the top of the contiguous stack of slabs, from the plate up, whose
  cross-section exceeds --pile-factor (default 2) times the jet's pi R^2: the mound (or
  heap of folds and coils) the jet piles up, / D. 0 before the jet reaches the plate.
- buckling indicator: the largest offset / D of the jet's axis, traced from the nozzle down
  to the pile: slab by slab from the top, the mass-weighted lateral centroid of the slab's
  particles within --trace (default 1) D of the centroid of the slab above (the nozzle axis
  for the top slab); the height of that slab / D, its two lateral components / D and its
  azimuth (degrees, as the band's below). The pile, and fluid away from the jet (a film or
  mound spreading unevenly over the plate, fluid leaving over one edge first), are left
  out: they shift slab centroids without the jet buckling. The largest centroid offset of
  whole slabs with the pile included (slabs holding at least a quarter of the jet's
  cross-section) is written too (largest_offset_with_pile_over_D). A straight jet keeps its
  axis on the nozzle's; a buckled jet folds or coils sideways by about its diameter just
  above the pile. The frame *buckles* when the indicator exceeds --threshold (default 0.25:
  the axis displaced by a quarter diameter, 2 dx at D = 8 dx).
- band offset and angle: the mass-weighted lateral centroid of the fluid in the band
  between the pile height and --band (default 1) D above it (the part of the jet just above
  the pile, which swings or coils), its offset / D and its azimuth in degrees, atan2 of its
  two lateral components (the axes after the nozzle axis a: (a + 2) mod 3 first, then
  (a + 1) mod 3; for a jet along y, atan2(z, x)).
- void measures: the largest nearest-neighbour distance over the fluid / dx, the number of
  isolated particles (no other fluid particle within 1.5 dx), and the void gap: the diameter
  of the largest empty sphere inside the fluid not open to the outside, / dx (the grid
  measure of drop_measure: an intact lattice gives at most 1.73, one missing particle 2;
  --no-voids skips it, it costs about a second a frame).
- void origin (vesph.measure.void_origin): each void is followed from frame to frame through
  the ids of the particles facing it. A void whose boundary particles faced the outside one
  frame before is a pocket the flow *enclosed* over the surrounding air (a fold or a coil
  laid on the pile: physical; at the free surface's pressure, as trapped air at ambient
  pressure would be); one whose boundary particles were inside the fluid *opened* there (a
  rupture: unphysical); a void that persists keeps its origin. Columns: the largest opened
  void and the largest enclosed pocket / dx (0 when none); a void of the first frame counts
  as opened.

Over the run
------------
- onset: the time of the first frame whose indicator exceeds --threshold (s and t U/D);
  none when no frame does.
- coiling frequency: from the indicator's azimuth after the onset, unwrapped: turns = its total
  change / 2 pi, and the frequency = the slope of a least-squares line through it / 2 pi
  (Hz, and f D/U) when the azimuth turned through at least one full turn; none otherwise.
  The azimuth is sampled at the frames: it resolves rotations slower than half a turn per
  frame (output interval).
- oscillation frequency: the zero crossings, about its mean, of the indicator's lateral
  offset after the onset along its direction of largest variance, / (2 x the time after the onset)
  (Hz): folding (a jet swinging in a plane) as well as coiling.

Checks (exit 1 when one fails)
------------------------------
--expect-buckling     some frame buckles (the indicator exceeds --threshold);
--expect-no-buckling  no frame buckles;
--max-void-gap G      every frame's void gap is at most G dx (e.g. 2.5: no unphysical void).
--max-opened-gap G    every frame's largest void opened inside the fluid is at most G dx (the
                      pockets enclosed over the outside are left out).

Outputs
-------
<prefix>_jet.csv (a row per frame), <prefix>_jet.png (indicator, band offset, azimuth, pile
height and the void gaps against t U/D) and <prefix>_jet_views.png (side views: the fluid
particles projected on the two vertical planes through the axis, at the frames nearest to
--pictures times in s, default four frames spread over the run), in --out-dir (default: the
file's directory); the prefix defaults to the scene name.

Exit status: 0 when the requested checks pass; 1 when one fails or the file cannot be used
(missing, not a vesph output, no circular nozzle, no plate, no frames); 2 for usage errors.
"""

import argparse
import csv
import math
import os
import sys

import numpy as np

from vesph import output as vesph_output
from vesph.output import Output, ToolError

PROG = "jet_buckling_measure"
ISOLATION = 1.5          # dx: a fluid particle with no other fluid particle this close is isolated


class Jet(Output):
    """The nozzle, the plate and the frames of one vesph jet-buckling output (a run still
    writing it may be measured)."""

    def __init__(self, path, plate=None):
        self._plate = plate
        super().__init__(path, live=True, partial_last_frame=True)

    def _check_scene(self):
        path, sc = self.path, self.scene
        if self.dim != 3:
            raise ToolError(f"{path}: a {self.dim}D output; jet buckling is 3D")
        inflow = sc.get("inflow")
        if not isinstance(inflow, dict) or "radius" not in inflow:
            raise ToolError(f"{path}: the scene has no circular nozzle ([inflow] with radius): "
                            "not a jet scene")
        try:
            direction = [float(v) for v in inflow["direction"]]
            lo = [float(v) for v in inflow["min"]]
            hi = [float(v) for v in inflow["max"]]
            self.R = float(inflow["radius"])
            self.U = float(inflow.get("mean_velocity", float("nan")))
        except (KeyError, TypeError, ValueError):
            raise ToolError(f"{path}: [inflow] lacks direction/min/max/radius")
        axes = [i for i, v in enumerate(direction) if v != 0.0]
        if len(axes) != 1:
            raise ToolError(f"{path}: [inflow] direction {direction} is not a coordinate axis")
        a = self.axis = axes[0]
        self.sign = 1.0 if direction[a] > 0 else -1.0          # the flow's sense along the axis
        self.lateral = [(a + 2) % 3, (a + 1) % 3]             # z, x for a jet along y
        self.centre = np.array([0.5 * (lo[i] + hi[i]) for i in self.lateral])
        self.inlet = hi[a] if self.sign > 0 else lo[a]
        if not (self.R > 0 and self.U > 0):
            raise ToolError(f"{path}: the nozzle needs radius > 0 and mean_velocity > 0 "
                            f"(got {self.R:g}, {self.U:g})")
        self.D = 2.0 * self.R
        if self._plate is not None:
            self.plate = float(self._plate)
            self.plate_note = f"--plate {self.plate:g} m"
        else:
            faces = []
            for b in sc.get("blocks", []):
                if b.get("kind") != "wall" or "min" not in b or "max" not in b:
                    continue
                face = float(b["max"][a]) if self.sign < 0 else float(b["min"][a])
                if (self.inlet - face) * -self.sign > 0:
                    faces.append(face)
            if not faces:
                raise ToolError(f"{path}: no wall box beyond the nozzle along its direction "
                                "(the plate); give --plate")
            self.plate = max(faces) if self.sign < 0 else min(faces)
            self.plate_note = "the wall box facing the nozzle"
        self.H = abs(self.inlet - self.plate)

    def read_fluid(self, k):
        """(heights above the plate [n], lateral positions about the axis [n, 2], volumes
        m/rho [n], positions [n, 3], ids [n]) of the fluid particles of frame k; None for an unreadable
        last frame of a run being written."""
        d = self.read_or_skip(k, ("kind", "position", "mass", "density", "id"))
        if d is None:
            return None
        fl = d["kind"] == 0
        pos = d["position"][fl]
        height = (pos[:, self.axis] - self.plate) * -self.sign
        lat = pos[:, self.lateral] - self.centre
        return height, lat, d["mass"][fl] / d["density"][fl], pos, d["id"][fl]


# -------------------------------------------------------------------------- measures
VOID_LINK = 1.5   # the open radius' link (drop.open_radius): 0.91 dx in 3D


def slab_profile(height, lat, vol, dx, H):
    """Per slab of thickness dx from the plate (0) to H: cross-section [m^2], lateral
    centroid [n_slabs, 2] (nan for an empty slab) and the slabs' lower edges."""
    n = max(1, int(math.ceil(H / dx)))
    k = np.floor(height / dx).astype(int)
    ok = (k >= 0) & (k < n)
    k, w, p = k[ok], vol[ok], lat[ok]
    v = np.bincount(k, weights=w, minlength=n)
    cx = np.bincount(k, weights=w * p[:, 0], minlength=n)
    cz = np.bincount(k, weights=w * p[:, 1], minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.column_stack([cx / v, cz / v])
    return v / dx, c, dx * np.arange(n)


def pile_height(area, edges, dx, jet_area, factor):
    """Top of the contiguous stack of slabs from the plate with area > factor x jet_area."""
    big = area > factor * jet_area
    if not big[0]:
        return 0.0
    stop = np.flatnonzero(~big)
    top = stop[0] if stop.size else len(big)
    return float(edges[0] + top * dx)


def buckling_indicator(area, centroid, edges, dx, jet_area, above=0.0):
    """(largest slab offset [m], the middle height of its slab [m], its lateral offset
    vector [2]) over the slabs from height `above` up that hold at least a quarter of the
    jet's cross-section; (0, nan, nan) when none does."""
    full = (area >= 0.25 * jet_area) & (edges >= above - 1e-9 * dx)
    if not np.any(full):
        return 0.0, float("nan"), np.array([float("nan"), float("nan")])
    off = np.hypot(centroid[:, 0], centroid[:, 1])
    off = np.where(full, off, -1.0)
    i = int(np.argmax(off))
    return float(off[i]), float(edges[i] + 0.5 * dx), centroid[i].copy()


def traced_axis(height, lat, vol, dx, H, pile, radius):
    """The jet's axis traced from the nozzle down to the pile: slab by slab (dx thick) from
    the top, the mass-weighted lateral centroid of the slab's particles within `radius` of
    the centroid of the slab above (the nozzle axis for the top slab); a slab with none keeps
    the one above. (largest offset [m], the middle height of its slab [m], its offset
    vector [2]); (0, nan, nan) when no slab above the pile holds particles near the axis."""
    n = max(1, int(math.ceil(H / dx)))
    k = np.floor(height / dx).astype(int)
    ok = (k >= 0) & (k < n) & (height >= pile)
    k, w, p = k[ok], vol[ok], lat[ok]
    order = np.argsort(k, kind="stable")
    k, w, p = k[order], w[order], p[order]
    starts = np.searchsorted(k, np.arange(n + 1))
    c = np.zeros(2)
    best, best_h, best_c = 0.0, float("nan"), np.array([float("nan"), float("nan")])
    for i in range(n - 1, -1, -1):
        lo, hi = starts[i], starts[i + 1]
        if hi == lo:
            continue
        near = np.hypot(p[lo:hi, 0] - c[0], p[lo:hi, 1] - c[1]) <= radius
        if not np.any(near):
            continue
        ww = w[lo:hi][near]
        c = (ww[:, None] * p[lo:hi][near]).sum(axis=0) / ww.sum()
        off = float(np.hypot(c[0], c[1]))
        if not math.isfinite(best_h) or off > best:
            best, best_h, best_c = off, (i + 0.5) * dx, c.copy()
    return best, best_h, best_c


def band_offset(height, lat, vol, lo, hi):
    """Mass-weighted lateral centroid [2] of the fluid with lo <= height < hi (nan if none)."""
    sel = (height >= lo) & (height < hi)
    if not np.any(sel):
        return np.array([float("nan"), float("nan")])
    w = vol[sel]
    return (w[:, None] * lat[sel]).sum(axis=0) / w.sum()


def isolation(pos, dx):
    """(largest nearest-neighbour distance / dx, particles with none within ISOLATION dx)."""
    from vesph.measure.drop import nearest_neighbour_distances

    d = nearest_neighbour_distances(pos)
    if d is None:
        return float("nan"), 0
    nn = d / dx
    return float(nn.max()), int(np.count_nonzero(nn > ISOLATION))


def onset(times, indicator, threshold):
    """Index of the first frame whose indicator exceeds threshold, or None."""
    above = np.flatnonzero(np.asarray(indicator) > threshold)
    return int(above[0]) if above.size else None


def coiling(times, angle_deg, start):
    """(turns, frequency [Hz] or nan) of the azimuth from frame start on: the unwrapped change
    / 360 degrees, and the slope of its least-squares line / 2 pi when it turned at least once."""
    t = np.asarray(times[start:], dtype=float)
    th = np.asarray(angle_deg[start:], dtype=float)
    ok = np.isfinite(th)
    t, th = t[ok], np.unwrap(np.radians(th[ok]))
    if len(t) < 3:
        return 0.0, float("nan")
    turns = (th[-1] - th[0]) / (2 * math.pi)
    if abs(turns) < 1.0:
        return float(turns), float("nan")
    slope = np.polyfit(t, th, 1)[0]
    return float(turns), float(abs(slope) / (2 * math.pi))


def oscillation(times, offsets, start):
    """Frequency [Hz] of the band offset's oscillation after frame start: its component along
    the direction of largest variance (principal axis: the plane of a fold, any direction of a
    coil), the zero crossings of it about its mean / (2 x the duration) (nan if none)."""
    t = np.asarray(times[start:], dtype=float)
    o = np.asarray(offsets[start:], dtype=float)
    ok = np.all(np.isfinite(o), axis=1)
    t, o = t[ok], o[ok]
    if len(t) < 3 or t[-1] <= t[0]:
        return float("nan")
    o = o - o.mean(axis=0)
    _, _, vt = np.linalg.svd(o, full_matrices=False)
    s = np.sign(o @ vt[0])
    s = s[s != 0]
    return float(np.count_nonzero(s[1:] != s[:-1]) / (2.0 * (t[-1] - t[0])))


def measure(jet, a):
    """Rows (dicts) for the frames of the file."""
    from vesph.measure import void_origin
    from vesph.measure.drop import grid_measures

    voids = void_origin.VoidTracker()
    dx, D, U, R = jet.dx, jet.D, jet.U, jet.R
    jet_area = math.pi * R * R
    rows = []
    jet.pictures = {}
    want = a.pictures if a.pictures else None
    if want is None:
        n = len(jet.frames)
        pick = sorted({int(round(i * (n - 1) / 3.0)) for i in range(4)})
    else:
        pick = sorted({int(np.argmin(np.abs(jet.times - w))) for w in want})
    for k, (nm, t) in enumerate(jet.frames):
        got = jet.read_fluid(k)
        if got is None:
            break
        height, lat, vol, pos, ids = got
        if len(height) == 0:
            raise ToolError(f"{jet.path}: frame {nm} has no fluid particles (kind 0)")
        if k in pick:
            jet.pictures[k] = (t, height.copy(), lat.copy())
        area, cen, edges = slab_profile(height, lat, vol, dx, jet.H)
        pile = pile_height(area, edges, dx, jet_area, a.pile_factor)
        ind, ind_h, ind_vec = traced_axis(height, lat, vol, dx, jet.H, pile, a.trace * D)
        whole = buckling_indicator(area, cen, edges, dx, jet_area)[0]
        band = band_offset(height, lat, vol, pile, min(pile + a.band * D, jet.H))
        nn, iso = isolation(pos, dx)
        vg = opened = enclosed = float("nan")
        if not a.no_voids:
            gm = grid_measures(pos, dx, VOID_LINK, 3.0, cracks=False)
            vg = gm["void_gap"] / dx
            found = voids.frame(pos, ids, gm["open_grid"])
            opened = void_origin.largest(found, void_origin.OPENED) / dx
            enclosed = void_origin.largest(found, void_origin.ENCLOSED) / dx
        rows.append({
            "frame": nm, "time_s": t, "tU_D": t * U / D, "n_fluid": len(height),
            "volume": float(vol.sum()),
            "pile_height_D": pile / D, "indicator_D": ind / D,
            "indicator_height_D": ind_h / D, "buckled": int(ind / D > a.threshold),
            "largest_offset_D": whole / D,
            "indicator_1_D": ind_vec[0] / D, "indicator_2_D": ind_vec[1] / D,
            "indicator_angle_deg": float(math.degrees(math.atan2(ind_vec[1], ind_vec[0])))
            if np.all(np.isfinite(ind_vec)) else float("nan"),
            "band_offset_D": float(np.hypot(*band)) / D,
            "band_lateral_1_D": band[0] / D, "band_lateral_2_D": band[1] / D,
            "band_angle_deg": float(math.degrees(math.atan2(band[1], band[0])))
            if np.all(np.isfinite(band)) else float("nan"),
            "max_nn_gap_dx": nn, "isolated": iso, "void_gap_dx": vg,
            "opened_gap_dx": opened, "enclosed_gap_dx": enclosed,
        })
    return rows


COLUMNS = [
    ("frame", "frame"), ("time_s", "time_s"), ("tU_D", "tU_over_D"), ("n_fluid", "n_fluid"),
    ("volume", "volume_m3"), ("pile_height_D", "pile_height_over_D"),
    ("indicator_D", "indicator_over_D"), ("indicator_height_D", "indicator_height_over_D"),
    ("largest_offset_D", "largest_offset_with_pile_over_D"),
    ("buckled", "buckled"), ("indicator_1_D", "indicator_offset_1_over_D"),
    ("indicator_2_D", "indicator_offset_2_over_D"), ("indicator_angle_deg", "indicator_angle_deg"),
    ("band_offset_D", "band_offset_over_D"),
    ("band_lateral_1_D", "band_offset_1_over_D"), ("band_lateral_2_D", "band_offset_2_over_D"),
    ("band_angle_deg", "band_angle_deg"), ("max_nn_gap_dx", "max_nn_gap_over_dx"),
    ("isolated", "isolated"), ("void_gap_dx", "void_gap_over_dx"),
    ("opened_gap_dx", "opened_void_gap_over_dx"), ("enclosed_gap_dx", "enclosed_pocket_gap_over_dx"),
]


def summarise(jet, rows, a):
    """Onset, coiling and oscillation over the run (a dict)."""
    t = np.array([r["time_s"] for r in rows])
    ind = np.array([r["indicator_D"] for r in rows])
    # --from: the frames before it (the initial column's fall) neither buckle nor count
    first = int(np.searchsorted(t, a.start - 1e-12 * max(1.0, abs(a.start))))
    if first >= len(t):
        raise ToolError(f"{a.h5file}: no frame at or after --from {a.start:g} s "
                        f"(the last at {t[-1]:.4g} s)")
    k0 = onset(t[first:], ind[first:], a.threshold)
    if k0 is not None:
        k0 += first
    s = {"onset_index": k0, "onset_s": float("nan"), "turns": 0.0,
         "coil_hz": float("nan"), "oscillation_hz": float("nan"),
         "max_indicator_D": float(np.max(ind[first:])),
         "max_indicator_all_D": float(np.max(ind)),
         "max_nn_gap_dx": float(np.nanmax([r["max_nn_gap_dx"] for r in rows])),
         "max_isolated": int(max(r["isolated"] for r in rows))}
    for key in ("void_gap_dx", "opened_gap_dx", "enclosed_gap_dx"):
        s["max_" + key] = float(np.nanmax([r[key] for r in rows])) if not a.no_voids else float("nan")
    if k0 is not None:
        s["onset_s"] = float(t[k0])
        s["turns"], s["coil_hz"] = coiling(t, [r["indicator_angle_deg"] for r in rows], k0)
        s["oscillation_hz"] = oscillation(
            t, [(r["indicator_1_D"], r["indicator_2_D"]) for r in rows], k0)
    return s


def write_csv(path, rows):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([h for _, h in COLUMNS])
        for r in rows:
            w.writerow([repr(float(r[k])) if isinstance(r[k], (float, np.floating)) else r[k]
                        for k, _ in COLUMNS])


def plot(png, jet, rows, s, a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = [r["tU_D"] for r in rows]
    col = lambda k: np.array([r[k] for r in rows], dtype=float)  # noqa: E731
    fig, axs = plt.subplots(2, 2, figsize=(11, 7.2), sharex=True)
    axs = axs.ravel()
    axs[0].plot(t, col("indicator_D"), "o-", ms=3, label="indicator: largest axis offset above the pile")
    axs[0].plot(t, col("largest_offset_D"), ":", color="0.5", label="largest offset, pile included")
    axs[0].plot(t, col("band_offset_D"), "s--", ms=3, label=f"band offset ({a.band:g} D above the pile)")
    axs[0].axhline(a.threshold, color="k", ls=":", lw=0.8, label=f"--threshold {a.threshold:g}")
    if s["onset_index"] is not None:
        axs[0].axvline(s["onset_s"] * jet.U / jet.D, color="r", lw=0.8, label="onset")
    axs[0].set_ylabel("offset / D")
    ang = col("indicator_angle_deg")
    ok = np.isfinite(ang)
    unwrapped = np.full(len(ang), np.nan)
    unwrapped[ok] = np.degrees(np.unwrap(np.radians(ang[ok])))
    axs[1].plot(t, unwrapped, "o-", ms=3)
    axs[1].set_ylabel("indicator azimuth, unwrapped [deg]")
    axs[2].plot(t, col("pile_height_D"), "o-", ms=3)
    axs[2].set_ylabel("pile height / D")
    axs[3].plot(t, col("void_gap_dx"), "-", label="void gap")
    axs[3].plot(t, col("opened_gap_dx"), "-", lw=0.8, label="void opened in the fluid")
    axs[3].plot(t, col("enclosed_gap_dx"), "-", lw=0.8, label="pocket enclosed from outside")
    axs[3].plot(t, col("max_nn_gap_dx"), "--", label="max nearest-neighbour gap")
    if a.max_opened_gap is not None:
        axs[3].axhline(a.max_opened_gap, color="r", ls=":", lw=0.8,
                       label=f"--max-opened-gap {a.max_opened_gap:g}")
    if a.max_void_gap is not None:
        axs[3].axhline(a.max_void_gap, color="k", ls=":", lw=0.8, label=f"--max-void-gap {a.max_void_gap:g}")
    axs[3].set_ylabel("gap / dx")
    for ax in axs:
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize="x-small")
    for ax in axs[2:]:
        ax.set_xlabel("t U / D")
    fig.suptitle(f"{jet.name}: H/D = {jet.H / jet.D:.3g}, D = {jet.D:g} m, U = {jet.U:g} m/s",
                 fontsize="medium")
    fig.tight_layout()
    fig.savefig(png, dpi=80)
    plt.close(fig)


def plot_views(png, jet):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ks = sorted(jet.pictures)
    names = "xyz"
    fig, axs = plt.subplots(2, len(ks), figsize=(2.4 * len(ks) + 0.6, 6.4), squeeze=False,
                            sharey=True)
    lim = 0.0
    for k in ks:
        lat = jet.pictures[k][2]
        if len(lat):
            lim = max(lim, float(np.abs(lat).max()))
    lim = max(lim / jet.D, 1.0) + 0.25
    for j, k in enumerate(ks):
        t, h, lat = jet.pictures[k]
        for i in range(2):
            ax = axs[i, j]
            ax.scatter(lat[:, 1 - i] / jet.D, h / jet.D, s=0.3, c="tab:blue", lw=0)
            ax.set_xlim(-lim, lim)
            ax.set_ylim(-0.2, jet.H / jet.D + 0.2)
            ax.set_aspect("equal")
            ax.axhline(0.0, color="k", lw=1)
            ax.set_xlabel(f"{names[jet.lateral[1 - i]]} / D")
            if j == 0:
                ax.set_ylabel("height / D")
            if i == 0:
                ax.set_title(f"t U/D = {t * jet.U / jet.D:.3g}", fontsize="small")
    fig.suptitle(f"{jet.name}: side views", fontsize="medium")
    fig.tight_layout()
    fig.savefig(png, dpi=70)
    plt.close(fig)


def fmt(v, f="{:.3g}"):
    return "none" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f.format(v)


def run(a):
    p = lambda *x: print(*x, flush=True)  # noqa: E731
    with Jet(a.h5file, a.plate) as jet:
        for n in jet.notes:
            p(f"note: {n}")
        rows = measure(jet, a)
        if not rows:
            raise ToolError(f"{a.h5file}: no frame could be read")
        s = summarise(jet, rows, a)
        out_dir = a.out_dir or os.path.dirname(os.path.abspath(a.h5file))
        os.makedirs(out_dir, exist_ok=True)
        prefix = a.prefix or jet.name
        written = [os.path.join(out_dir, prefix + "_jet.csv")]
        write_csv(written[0], rows)
        if not a.no_png:
            written.append(os.path.join(out_dir, prefix + "_jet.png"))
            plot(written[-1], jet, rows, s, a)
            written.append(os.path.join(out_dir, prefix + "_jet_views.png"))
            plot_views(written[-1], jet)
        nu = float(jet.scene.get("fluid", {}).get("viscosity", float("nan"))) / float(
            jet.scene.get("fluid", {}).get("density", float("nan")))
        p(f"{jet.name}: D = {jet.D:g} m, U = {jet.U:g} m/s, H = {jet.H:g} m (H/D = {jet.H / jet.D:.3g}; "
          f"plate at {jet.plate:g} m: {jet.plate_note}), Re = U D/nu = {jet.U * jet.D / nu:.3g} "
          f"(nu = solvent viscosity / density), {len(rows)} frames to t = {rows[-1]['time_s']:.4g} s "
          f"(t U/D = {rows[-1]['tU_D']:.3g})")
        p(f"  {'t [s]':>8s} {'tU/D':>7s} {'fluid':>7s} {'pile/D':>7s} {'ind/D':>7s} {'at h/D':>7s} "
          f"{'band/D':>7s} {'angle':>7s} {'nn/dx':>6s} {'isol':>5s} {'void/dx':>7s} {'opened':>7s} "
          f"{'pocket':>7s}")
        for r in rows:
            p(f"  {r['time_s']:8.4f} {r['tU_D']:7.2f} {r['n_fluid']:7d} {r['pile_height_D']:7.2f} "
              f"{r['indicator_D']:7.3f} {r['indicator_height_D']:7.2f} {r['band_offset_D']:7.3f} "
              f"{r['indicator_angle_deg']:7.1f} {r['max_nn_gap_dx']:6.2f} {r['isolated']:5d} "
              f"{r['void_gap_dx']:7.2f} {r['opened_gap_dx']:7.2f} {r['enclosed_gap_dx']:7.2f}")
        U_D = jet.U / jet.D
        if a.start > 0:
            p(f"from t = {a.start:g} s (t U/D = {a.start * jet.U / jet.D:.3g}) on: largest buckling "
              f"indicator {s['max_indicator_D']:.3f} D (threshold {a.threshold:g} D; over the whole run "
              f"{s['max_indicator_all_D']:.3f} D)")
        else:
            p(f"largest buckling indicator {s['max_indicator_D']:.3f} D (threshold {a.threshold:g} D)")
        if s["onset_index"] is None:
            p("onset: none (no frame buckles)")
        else:
            p(f"onset: t = {s['onset_s']:.4g} s (t U/D = {s['onset_s'] * U_D:.3g})")
            p(f"coiling: {s['turns']:+.2f} turns of the indicator's azimuth after the onset; frequency "
              f"{fmt(s['coil_hz'])} Hz (f D/U = {fmt(s['coil_hz'] / U_D)})")
            p(f"oscillation of the indicator's offset after the onset: {fmt(s['oscillation_hz'])} Hz "
              f"(f D/U = {fmt(s['oscillation_hz'] / U_D)})")
        void_gap = "not measured (--no-voids)" if a.no_voids else f"{fmt(s['max_void_gap_dx'])} dx"
        p(f"voids: largest void gap {void_gap}, largest nearest-neighbour "
          f"gap {fmt(s['max_nn_gap_dx'])} dx, at most {s['max_isolated']} isolated particles")
        if not a.no_voids:
            p(f"  of which: the largest void opened inside the fluid {fmt(s['max_opened_gap_dx'])} dx, "
              f"the largest pocket enclosed from the outside {fmt(s['max_enclosed_gap_dx'])} dx "
              f"(0: none)")
        for w in written:
            p(f"wrote {w}")
        ok = True
        if a.expect_buckling and s["onset_index"] is None:
            p(f"CHECK FAILED: --expect-buckling: the indicator stays at or below {a.threshold:g} D "
              f"(largest {s['max_indicator_D']:.3f} D)")
            ok = False
        if a.expect_no_buckling and s["onset_index"] is not None:
            p(f"CHECK FAILED: --expect-no-buckling: the indicator reaches "
              f"{s['max_indicator_D']:.3f} D > {a.threshold:g} D (first at t = {s['onset_s']:.4g} s)")
            ok = False
        if a.max_void_gap is not None and not a.no_voids and s["max_void_gap_dx"] > a.max_void_gap:
            p(f"CHECK FAILED: --max-void-gap: a void of {s['max_void_gap_dx']:.2f} dx > "
              f"{a.max_void_gap:g} dx")
            ok = False
        if a.max_opened_gap is not None and s["max_opened_gap_dx"] > a.max_opened_gap:
            p(f"CHECK FAILED: --max-opened-gap: a void opened inside the fluid of "
              f"{s['max_opened_gap_dx']:.2f} dx > {a.max_opened_gap:g} dx")
            ok = False
        if (a.expect_buckling or a.expect_no_buckling or a.max_void_gap is not None
                or a.max_opened_gap is not None):
            p("RESULT: " + ("PASS" if ok else "FAIL"))
        return 0 if ok else 1


times_list = vesph_output.nonnegative_list("times [s]")


def main(argv=None):
    ap = argparse.ArgumentParser(
        prog="jet_buckling_measure",
        description="Buckling indicator, onset, coiling frequency, pile height and voids of a "
                    "vesph jet-buckling run (3D, a circular nozzle above a plate), as CSV and PNG.")
    ap.add_argument("h5file", metavar="H5FILE", help="vesph output file (.h5)")
    ap.add_argument("--out-dir", metavar="DIR", help="directory for the CSV and PNG (default: the file's)")
    ap.add_argument("--prefix", metavar="NAME", help="file name prefix (default: the scene name)")
    ap.add_argument("--no-png", action="store_true", help="write the CSV only")
    ap.add_argument("--threshold", type=float, default=0.25, metavar="B",
                    help="a frame buckles when the axis offset exceeds B D (default 0.25)")
    ap.add_argument("--pile-factor", type=float, default=2.0, metavar="F",
                    help="the pile: slabs whose cross-section exceeds F pi R^2 (default 2)")
    ap.add_argument("--band", type=float, default=1.0, metavar="L",
                    help="the band above the pile whose offset and azimuth are followed, "
                         "L D high (default 1)")
    ap.add_argument("--trace", type=float, default=1.0, metavar="T",
                    help="the jet's axis is traced through the particles within T D of the "
                         "axis in the slab above (default 1)")
    ap.add_argument("--plate", type=float, metavar="Y",
                    help="the plate's coordinate along the nozzle axis [m] (default: the wall "
                         "box facing the nozzle)")
    ap.add_argument("--pictures", type=times_list, metavar="T1,T2,...",
                    help="side views at the frames nearest to these times [s] (default: four "
                         "frames spread over the run)")
    ap.add_argument("--from", dest="start", type=float, default=0.0, metavar="T",
                    help="the onset, the largest indicator and the buckling checks count the "
                         "frames from time T [s] on (default 0: all); e.g. the transit time of "
                         "an initial column, about H/U")
    ap.add_argument("--no-voids", action="store_true", help="skip the void gap (grid measure)")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--expect-buckling", action="store_true", help="check: some frame buckles")
    g.add_argument("--expect-no-buckling", action="store_true", help="check: no frame buckles")
    ap.add_argument("--max-void-gap", type=float, metavar="G",
                    help="check: every frame's void gap is at most G dx (e.g. 2.5)")
    ap.add_argument("--max-opened-gap", type=float, metavar="G",
                    help="check: every void that opened inside the fluid (not a pocket the flow "
                         "enclosed over the outside) is at most G dx in every frame")
    a = ap.parse_args(argv)
    if not (math.isfinite(a.start) and a.start >= 0):
        ap.error(f"--from must be a time >= 0 [s], got {a.start:g}")
    for nm, v in (("--threshold", a.threshold), ("--pile-factor", a.pile_factor), ("--band", a.band),
                  ("--trace", a.trace)):
        if not (math.isfinite(v) and v > 0):
            ap.error(f"{nm} must be a positive number, got {v:g}")
    if a.max_void_gap is not None and not (a.max_void_gap > 0):
        ap.error(f"--max-void-gap must be positive, got {a.max_void_gap:g}")
    if a.max_void_gap is not None and a.no_voids:
        ap.error("--max-void-gap needs the void gap: not with --no-voids")
    if a.max_opened_gap is not None and not (a.max_opened_gap > 0):
        ap.error(f"--max-opened-gap must be positive, got {a.max_opened_gap:g}")
    if a.max_opened_gap is not None and a.no_voids:
        ap.error("--max-opened-gap needs the void measures: not with --no-voids")
    return vesph_output.run_reporting_errors(PROG, run, a)


if __name__ == "__main__":
    sys.exit(main())
