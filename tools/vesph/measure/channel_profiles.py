#!/usr/bin/python3
"""Extract the centreline history and the cross-channel profiles of a vesph channel run.

Works for start-up (or any) plane channel flow between walls normal to y, for any fluid
model: Newtonian, Oldroyd-B, UCM, XPP, second-order fluid... The tool only reads what the
output holds (user-guide.md section 4, format vesph-1); nothing is compared with a theory.

Usage
-----
    /usr/bin/python3 tools/startup_channel_profiles.py H5FILE
        [--stations X1,X2,...] [--times T1,T2,... | --all-times] [--bin-width DX]
        [--out-dir DIR] [--prefix NAME] [--no-png]

Inputs
------
From the file: the frames (time, kind, position, velocity and, when a viscoelastic model is
on, extra_stress = T, the full extra stress, xx/xy/yy in 2D, xx/xy/xz/yy/yz/zz in 3D) and
the resolved scene (root attribute ``scene``): the channel is the extent of the fluid blocks,
y in [y0, y1], centre y_c = (y0 + y1)/2, half-width a = (y1 - y0)/2, x in [x0, x1]; the
spacing dx is the root attribute ``dx`` (else particles.spacing); x is periodic when
domain.periodic[0] is true.

Rows: in each frame the fluid particles are grouped into rows by clustering their y: sorted y
values are split wherever the gap between neighbours exceeds dx/2. On a (slightly perturbed)
lattice this gives one cluster per particle row. If a cluster spans more than dx/2 in y (the
lattice has been disordered so that rows merge), the frame falls back to bins of width dx
anchored at y0 (the rows of the initial lattice) and says so.

Outputs (all SI: m, s, m/s, Pa)
-------------------------------
1. Centreline history, every frame: time, centreline velocity v_c, max |T_xy| and max N1
   over all fluid particles (N1 = T_xx - T_yy).
   Centreline rule: the one or two particle rows nearest the centre line. With d_k the
   distance |mean y of row k - y_c| and d_min the smallest, the rows with
   d_k <= d_min + dx/4 are taken, over the whole channel length (all x): on a lattice that is
   the central row (odd number of rows) or the two rows at y_c +- dx/2 (even number).
   v_c is the mean x-velocity of all particles in those rows.
   -> DIR/<prefix>_centreline.csv and DIR/<prefix>_centreline.png
2. Profiles at each station x_s (--stations, default the middle of the channel) and each
   requested time (--times: the nearest frame; default the last frame; --all-times: every
   frame): the fluid particles with |x - x_s| <= bin_width/2 (distance taken periodically
   along a periodic x; default bin width dx, i.e. one particle per row on the lattice, two
   where x_s falls half-way between lattice columns) are averaged per row: y, Y = (y - y_c)/a,
   v_x, T_xx, T_xy, T_yy, N1 and the number of particles averaged (count; a row with no
   particle in the bin is written with count 0 and nan values).
   -> DIR/<prefix>_profiles.csv (long format, one line per station, time and row) and
      DIR/<prefix>_profiles.png (panels v_x, T_xx, T_xy, T_yy, N1 against y, one line per
      station and time).
When the frames have no extra_stress (a Newtonian run) this is said, and only the velocity
columns and panels are written (no stress is reconstructed from velocity gradients).

--out-dir defaults to the directory of H5FILE, --prefix to the scene name.
A short summary table is printed to stdout.

Exit status: 0 on success; 1 when the file cannot be used (missing, not HDF5, not a vesph
output, no fluid particles, inconsistent datasets); 2 for usage errors (bad options, a
station outside the channel, a time outside the output range).
"""

import argparse
import csv
import math
import os
import sys

import numpy as np

from vesph import output as vesph_output
from vesph.output import Output, ToolError

GENERIC_EFFECTS = {"continuity", "equation_of_state", "pressure_gradient", "viscosity",
                   "body_force", "velocity_gradient", "stress_divergence"}
PROG = "startup_channel_profiles"


# ----------------------------------------------------------------------------- reading
class Channel(Output):
    """The channel geometry and the frames of one vesph output file."""

    def __init__(self, path):
        super().__init__(path)
        # (name, time, step) of each frame
        self.frames = [(nm, t, step) for (nm, t), step in zip(self.frames, self.steps)]
        self.has_stress = self.has(0, "extra_stress")

    def _check_scene(self):
        """The channel's geometry from the scene's fluid blocks and domain."""
        path, sc = self.path, self.scene
        blocks = [b for b in sc.get("blocks", []) if b.get("kind") == "fluid"]
        if not blocks:
            raise ToolError(f"{path}: the scene has no fluid block ([[blocks]] kind = "
                            "\"fluid\"): no fluid particles")
        self.y0 = min(float(b["min"][1]) for b in blocks)
        self.y1 = max(float(b["max"][1]) for b in blocks)
        self.x0 = min(float(b["min"][0]) for b in blocks)
        self.x1 = max(float(b["max"][0]) for b in blocks)
        self.yc = 0.5 * (self.y0 + self.y1)
        self.a = 0.5 * (self.y1 - self.y0)
        dom = sc.get("domain", {})
        per = dom.get("periodic", [False] * self.dim)
        self.periodic = bool(per[0]) if per else False
        if self.periodic:
            self.length = float(dom["max"][0]) - float(dom["min"][0])
        else:
            self.length = self.x1 - self.x0
        self.model = {k: v for k, v in sc.get("effects", {}).items()
                      if k not in GENERIC_EFFECTS}

    def read_fluid(self, i):
        """Fluid data of frame i: dict with x, y, vx and (when present) txx, txy, tyy."""
        name = self.frames[i][0]
        if self.has_stress and not self.has(i, "extra_stress"):
            raise ToolError(f"{self.path}: frame {name} has no extra_stress, frame "
                            f"{self.frames[0][0]} has")
        g = self.read(i, ("kind", "position", "velocity") + (("extra_stress",) if self.has_stress else ()))
        fl = g["kind"] == 0
        if not np.any(fl):
            raise ToolError(f"{self.path}: frame {name} (t = {self.frames[i][1]:.6g} s) has "
                            "no fluid particles (kind 0)")
        pos, vel = g["position"], g["velocity"]
        d = {"x": pos[fl, 0], "y": pos[fl, 1], "vx": vel[fl, 0]}
        if self.has_stress:
            T = g["extra_stress"][fl]
            iyy = 2 if self.dim == 2 else 3        # 2D: xx xy yy; 3D: xx xy xz yy yz zz
            d["txx"], d["txy"], d["tyy"] = T[:, 0], T[:, 1], T[:, iyy]
        return d


# ------------------------------------------------------------------------------ rows
def cluster_rows(y, dx, y0):
    """Row label of each particle (0 = lowest row) and the method used.

    Sorted y values are split where the gap exceeds dx/2; if a cluster then spans more than
    dx/2, the rows are bins of width dx anchored at y0 instead."""
    y = np.asarray(y, dtype=float)
    order = np.argsort(y, kind="stable")
    ys = y[order]
    brk = np.zeros(len(ys), dtype=np.int64)
    if len(ys) > 1:
        brk[1:] = np.diff(ys) > 0.5 * dx
    lab_sorted = np.cumsum(brk)
    nrow = int(lab_sorted[-1]) + 1 if len(ys) else 0
    lo = np.full(nrow, np.inf)
    hi = np.full(nrow, -np.inf)
    np.minimum.at(lo, lab_sorted, ys)
    np.maximum.at(hi, lab_sorted, ys)
    if nrow == 0 or np.max(hi - lo) <= 0.5 * dx:
        labels = np.empty(len(y), dtype=np.int64)
        labels[order] = lab_sorted
        return labels, nrow, "clustered"
    k = np.floor((y - y0) / dx).astype(np.int64)
    uniq, labels = np.unique(k, return_inverse=True)
    return labels.astype(np.int64), len(uniq), "lattice bins (rows too disordered to cluster)"


def row_means(labels, nrow, values, mask=None):
    """Per-row mean of values over the particles selected by mask; (means, counts)."""
    if mask is None:
        mask = np.ones(len(labels), dtype=bool)
    cnt = np.bincount(labels[mask], minlength=nrow).astype(float)
    s = np.bincount(labels[mask], weights=np.asarray(values, dtype=float)[mask], minlength=nrow)
    with np.errstate(invalid="ignore", divide="ignore"):
        m = np.where(cnt > 0, s / np.where(cnt > 0, cnt, 1.0), np.nan)
    return m, cnt.astype(np.int64)


def centreline(d, labels, nrow, ch):
    """(v_c, number of particles, rows used): mean vx of the rows nearest y_c."""
    ym, _ = row_means(labels, nrow, d["y"])
    dist = np.abs(ym - ch.yc)
    use = dist <= np.nanmin(dist) + 0.25 * ch.dx
    sel = use[labels]
    return float(np.mean(d["vx"][sel])), int(np.count_nonzero(sel)), np.flatnonzero(use)


def in_bin(x, xs, bw, ch):
    dxs = np.asarray(x, dtype=float) - xs
    if ch.periodic and ch.length > 0:
        dxs = dxs - ch.length * np.round(dxs / ch.length)
    return np.abs(dxs) <= 0.5 * bw + 1e-9 * ch.dx


def profile(d, labels, nrow, xs, bw, ch):
    """Rows (list of dicts) of the profile at station xs."""
    mask = in_bin(d["x"], xs, bw, ch)
    ym, cnt = row_means(labels, nrow, d["y"], mask)
    cols = {"y": ym, "vx": row_means(labels, nrow, d["vx"], mask)[0]}
    if ch.has_stress:
        for c in ("txx", "txy", "tyy"):
            cols[c] = row_means(labels, nrow, d[c], mask)[0]
        cols["n1"] = row_means(labels, nrow, d["txx"] - d["tyy"], mask)[0]
    # rows with nobody in the bin: y from the whole row, values nan
    yall, _ = row_means(labels, nrow, d["y"])
    cols["y"] = np.where(cnt > 0, ym, yall)
    out = []
    for k in range(nrow):
        r = {c: float(v[k]) for c, v in cols.items()}
        r["Y"] = (r["y"] - ch.yc) / ch.a
        r["count"] = int(cnt[k])
        out.append(r)
    return out


# ---------------------------------------------------------------------------- options
def float_list(text):
    try:
        vals = [float(s) for s in text.split(",") if s.strip() != ""]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}")
    if not vals:
        raise argparse.ArgumentTypeError("expected at least one number")
    if not all(math.isfinite(v) for v in vals):
        raise argparse.ArgumentTypeError(f"non-finite value in {text!r}")
    return vals


def select_frames(ch, times, all_times):
    """Indices of the frames for the profiles and (requested, used) notes."""
    if all_times:
        return list(range(len(ch.frames))), []
    if not times:
        return [len(ch.frames) - 1], []
    t0, t1 = float(ch.times.min()), float(ch.times.max())
    tol = 1e-9 * max(abs(t0), abs(t1), 1e-300)
    idx, notes = [], []
    for T in times:
        if T < t0 - tol or T > t1 + tol:
            raise ToolError(f"time {T:g} s is outside the output range [{t0:g}, {t1:g}] s "
                            f"of {ch.path}", 2)
        i = int(np.argmin(np.abs(ch.times - T)))
        if abs(ch.times[i] - T) > tol:
            notes.append(f"time {T:g} s: nearest frame {ch.frames[i][0]} at t = "
                         f"{ch.times[i]:.6g} s")
        if i not in idx:
            idx.append(i)
    return sorted(idx), notes


def check_stations(ch, stations):
    if stations is None:
        return [0.5 * (ch.x0 + ch.x1)]
    tol = 1e-9 * max(ch.x1 - ch.x0, ch.dx)
    for s in stations:
        if s < ch.x0 - tol or s > ch.x1 + tol:
            raise ToolError(f"station x = {s:g} m is outside the channel, x in "
                            f"[{ch.x0:g}, {ch.x1:g}] m (the fluid blocks)", 2)
    return list(dict.fromkeys(stations))


# ----------------------------------------------------------------------------- output
def _nanmax(vals):
    """Largest finite-or-inf value, nan when all are nan (no warning)."""
    v = np.asarray(vals, dtype=float)
    v = v[~np.isnan(v)]
    return float(v.max()) if v.size else float("nan")


def _fmt(v):
    return repr(float(v)) if isinstance(v, (float, np.floating)) else str(v)


def write_csv(path, header, rows):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow([_fmt(v) for v in r])


def plot_centreline(png, hist, ch, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = 3 if ch.has_stress else 1
    fig, axs = plt.subplots(n, 1, figsize=(6.4, 2.6 * n + 0.6), sharex=True, squeeze=False)
    t = [h["t"] for h in hist]
    series = [("vc", "centreline v_x [m/s]")]
    if ch.has_stress:
        series += [("txy", "max |T_xy| [Pa]"), ("n1", "max N1 [Pa]")]
    for ax, (key, lab) in zip(axs[:, 0], series):
        ax.plot(t, [h[key] for h in hist], "o-", ms=3)
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
    axs[-1, 0].set_xlabel("t [s]")
    axs[0, 0].set_title(title)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def plot_profiles(png, curves, ch, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [("vx", "v_x [m/s]")]
    if ch.has_stress:
        panels += [("txx", "T_xx [Pa]"), ("txy", "T_xy [Pa]"), ("tyy", "T_yy [Pa]"),
                   ("n1", "N1 = T_xx - T_yy [Pa]")]
    if len(panels) == 1:
        fig, axs = plt.subplots(1, 1, figsize=(6.4, 4.8), squeeze=False)
    else:
        fig, axs = plt.subplots(2, 3, figsize=(14, 8), squeeze=False)
    axs = axs.ravel()
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    styles = ["-", "--", ":", "-."]
    for ax, (key, lab) in zip(axs, panels):
        for label, it, js, rows in curves:
            y = [r["y"] for r in rows if r["count"] > 0]
            v = [r[key] for r in rows if r["count"] > 0]
            ax.plot(y, v, marker=".", ms=3, lw=1, ls=styles[js % len(styles)],
                    color=colors[it % len(colors)], label=label)
        ax.set_xlabel("y [m]")
        ax.set_ylabel(lab)
        ax.axvline(ch.yc, color="k", lw=0.5, alpha=0.4)
        ax.grid(alpha=0.3)
    if len(axs) > len(panels):
        leg = axs[len(panels)]
        leg.axis("off")
        h, lab = axs[0].get_legend_handles_labels()
        leg.legend(h, lab, loc="center", fontsize="small")
        for ax in axs[len(panels) + 1:]:
            ax.axis("off")
    else:
        axs[0].legend(fontsize="small")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def describe_model(ch):
    if not ch.model:
        return "Newtonian (no constitutive-model effect)"
    parts = []
    for k, v in ch.model.items():
        if isinstance(v, dict) and v:
            parts.append(k + " (" + ", ".join(f"{kk} = {vv}" for kk, vv in v.items()) + ")")
        else:
            parts.append(k)
    return "; ".join(parts)


# ------------------------------------------------------------------------------- main
def run(a, out=sys.stdout):
    ch = Channel(a.h5file)
    try:
        return _run(ch, a, out)
    finally:
        ch.close()


def _run(ch, a, out):
    stations = check_stations(ch, a.stations)
    bw = ch.dx if a.bin_width is None else a.bin_width
    if not (bw > 0):
        raise ToolError(f"--bin-width must be > 0, got {bw:g}", 2)
    sel, notes = select_frames(ch, a.times, a.all_times)
    out_dir = a.out_dir if a.out_dir is not None else (os.path.dirname(os.path.abspath(a.h5file)))
    prefix = a.prefix or str(ch.scene.get("name", os.path.splitext(os.path.basename(a.h5file))[0]))
    os.makedirs(out_dir, exist_ok=True)

    p = lambda *s: print(*s, file=out)  # noqa: E731
    p(f"file: {ch.path}")
    p(f"scene: {ch.scene.get('name', '?')} ({ch.dim}D); model: {describe_model(ch)}; "
      f"solvent/Newtonian viscosity fluid.viscosity = "
      f"{ch.scene.get('fluid', {}).get('viscosity', '?')} Pa s")
    p(f"channel: y in [{ch.y0:.6g}, {ch.y1:.6g}] m, y_c = {ch.yc:.6g} m, a = {ch.a:.6g} m; "
      f"x in [{ch.x0:.6g}, {ch.x1:.6g}] m ({'periodic' if ch.periodic else 'not periodic'}); "
      f"dx = {ch.dx:.6g} m")
    p(f"frames: {len(ch.frames)}, t = {ch.times.min():.6g} ... {ch.times.max():.6g} s; "
      + ("extra_stress present: T_xx, T_xy, T_yy, N1 = T_xx - T_yy" if ch.has_stress else
         "no extra_stress in the frames (not a viscoelastic run): only the velocity is "
         "written"))

    # centreline history (every frame) and profiles (selected frames)
    hist, prof_rows, curves, summary = [], [], [], []
    methods = {}
    for i, (name, t, step) in enumerate(ch.frames):
        d = ch.read_fluid(i)
        labels, nrow, method = cluster_rows(d["y"], ch.dx, ch.y0)
        methods.setdefault(method, []).append(name)
        vc, nc, used = centreline(d, labels, nrow, ch)
        h = {"frame": name, "t": t, "step": step, "vc": vc, "nc": nc, "nrow": nrow}
        if ch.has_stress:
            h["txy"] = float(np.max(np.abs(d["txy"])))
            h["n1"] = float(np.max(d["txx"] - d["tyy"]))
        hist.append(h)
        if i not in sel:
            continue
        for js, xs in enumerate(stations):
            rows = profile(d, labels, nrow, xs, bw, ch)
            curves.append((f"x = {xs:.4g} m, t = {t:.4g} s", sel.index(i), js, rows))
            for r in rows:
                line = [xs, t, name, r["y"], r["Y"], r["vx"]]
                if ch.has_stress:
                    line += [r["txx"], r["txy"], r["tyy"], r["n1"]]
                prof_rows.append(line + [r["count"]])
            cnts = [r["count"] for r in rows]
            s = {"xs": xs, "t": t, "frame": name, "rows": nrow, "n": int(sum(cnts)),
                 "cmin": min(cnts), "cmax": max(cnts),
                 "vmax": _nanmax([r["vx"] for r in rows])}
            if ch.has_stress:
                s["txy"] = _nanmax([abs(r["txy"]) for r in rows])
                s["n1"] = _nanmax([r["n1"] for r in rows])
            summary.append(s)

    for m, names in methods.items():
        p(f"rows: {m} in {len(names)} frame(s)"
          + ("" if m == "clustered" else f" (first: frame {names[0]})"))
    p(f"centreline rule: mean v_x of the row(s) nearest y_c (within d_min + dx/4), all x; "
      f"{hist[-1]['nc']} particles in the last frame")
    for n in notes:
        p("note: " + n)

    # centreline table (at most ~12 lines)
    step = max(1, math.ceil(len(hist) / 10))
    show = sorted(set(range(0, len(hist), step)) | {len(hist) - 1})
    hdr = f"{'frame':>8} {'t [s]':>11} {'v_c [m/s]':>13}"
    if ch.has_stress:
        hdr += f" {'max|T_xy| [Pa]':>15} {'max N1 [Pa]':>13}"
    p("centreline history" + (f" (every {step} frames and the last)" if step > 1 else "") + ":")
    p(hdr)
    for j in show:
        h = hist[j]
        line = f"{h['frame']:>8} {h['t']:11.5g} {h['vc']:13.5g}"
        if ch.has_stress:
            line += f" {h['txy']:15.5g} {h['n1']:13.5g}"
        p(line)
    jmax = int(np.argmax([h["vc"] for h in hist]))
    p(f"peak centreline velocity {hist[jmax]['vc']:.5g} m/s at t = {hist[jmax]['t']:.5g} s; "
      f"last {hist[-1]['vc']:.5g} m/s at t = {hist[-1]['t']:.5g} s")

    p(f"profiles: bin |x - x_s| <= {0.5 * bw:.4g} m"
      + (" (periodic distance)" if ch.periodic else "") + ":")
    hdr = (f"{'x_s [m]':>10} {'t [s]':>10} {'frame':>7} {'rows':>5} {'particles':>9} "
           f"{'count/row':>9} {'max v_x [m/s]':>13}")
    if ch.has_stress:
        hdr += f" {'max|T_xy| [Pa]':>14} {'max N1 [Pa]':>12}"
    p(hdr)
    for s in summary:
        cr = f"{s['cmin']}" if s["cmin"] == s["cmax"] else f"{s['cmin']}-{s['cmax']}"
        line = (f"{s['xs']:10.4g} {s['t']:10.5g} {s['frame']:>7} {s['rows']:5d} {s['n']:9d} "
                f"{cr:>9} {s['vmax']:13.5g}")
        if ch.has_stress:
            line += f" {s['txy']:14.5g} {s['n1']:12.5g}"
        p(line)
        if s["cmin"] == 0:
            p(f"  note: some rows have no particle within the bin at x_s = {s['xs']:g} m "
              "(written with count 0 and nan); widen --bin-width")

    base = os.path.join(out_dir, prefix)
    hc = ["frame", "time_s", "step", "vx_centre_m_s", "n_centre"]
    if ch.has_stress:
        hc += ["max_abs_Txy_Pa", "max_N1_Pa"]
    write_csv(base + "_centreline.csv", hc,
              [[h["frame"], h["t"], h["step"], h["vc"], h["nc"]]
               + ([h["txy"], h["n1"]] if ch.has_stress else []) for h in hist])
    hp = ["station_x_m", "time_s", "frame", "y_m", "Y", "vx_m_s"]
    if ch.has_stress:
        hp += ["Txx_Pa", "Txy_Pa", "Tyy_Pa", "N1_Pa"]
    hp += ["count"]
    write_csv(base + "_profiles.csv", hp, prof_rows)
    written = [base + "_centreline.csv", base + "_profiles.csv"]
    if not a.no_png:
        title = str(ch.scene.get("name", ""))
        plot_centreline(base + "_centreline.png", hist, ch, title)
        plot_profiles(base + "_profiles.png", curves, ch, title)
        written += [base + "_centreline.png", base + "_profiles.png"]
    for w in written:
        p(f"wrote {w}")
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(
        prog="startup_channel_profiles.py",
        description="Centreline history and cross-channel profiles (v_x, T_xx, T_xy, T_yy, "
                    "N1) of a vesph channel-flow output, as CSV and PNG.")
    ap.add_argument("h5file", metavar="H5FILE", help="vesph output file (.h5)")
    ap.add_argument("--stations", type=float_list, metavar="X1,X2,...",
                    help="positions x [m] along the channel for the profiles "
                         "(default: the middle of the channel)")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--times", type=float_list, metavar="T1,T2,...",
                   help="times [s] for the profiles; the nearest frame is used "
                        "(default: the last frame)")
    g.add_argument("--all-times", action="store_true", help="profiles at every frame")
    ap.add_argument("--bin-width", type=float, metavar="DX",
                    help="width [m] of the x-bin averaged at each station "
                         "(default: the particle spacing)")
    ap.add_argument("--out-dir", metavar="DIR",
                    help="directory for the CSV and PNG files (default: that of H5FILE)")
    ap.add_argument("--prefix", metavar="NAME",
                    help="file name prefix (default: the scene name)")
    ap.add_argument("--no-png", action="store_true", help="write the CSV files only")
    a = ap.parse_args(argv)
    return vesph_output.run_reporting_errors(PROG, run, a)


if __name__ == "__main__":
    sys.exit(main())
