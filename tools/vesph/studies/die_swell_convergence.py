#!/usr/bin/python3
"""The Newtonian die swell under refinement: `die_swell_study.py convergence` (issue 35).

Usage
-----
    /usr/bin/python3 tools/die_swell_study.py convergence
        [--across N N N ...] [--re RE ...] [--end T] [--interval T] [--stations X ...]
        [--wall-floor P] [--xsph EPS] [--delta D] [--shifting A] [--artificial-stress EPS] [--sound-speed C]
        [--integrator TYPE] [--smoothing-ratio R] [--viscous-form FORM] [--scheme wcsph|isph] [--surface-pressure zero|normal_stress] [--dry-walls include|omit] [--jobs J] [--out DIR] [--vesph PATH]
        [--dry-run] [--measure-only] [--no-png] [--compare]

Runs the Newtonian planar die of cases/die_swell_newtonian.toml (W = 0.01 m, exit x = 0.2 m,
rho = 1000 kg/m^3, feed of mean velocity U = 0.5 m/s, delta-SPH 0.1 + XSPH 0.5, leapfrog; the
study's baseline has Morris' Laplacian, every wall particle in the pressure force and no
particle shifting, as the case had until session 25: the case's own settings are the variants
--viscous-form stress_renormalised --shifting 1 --wetted-faces, since session 26) at
each resolution --across (particles across the die, default 10 16 25; dx = W/N, h = 1.6 dx,
five dummy layers and a five-column buffer) and each Reynolds number --re (default 0.5 and
0.01; Re = rho W U / mu: the viscosity is mu = rho W U / Re, U and rho stay the case's).
The sound speed keeps the case's compressibility: the die's pressure drop 12 mu U L / W^2
grows as 1/Re, so c = 40 m/s * sqrt(0.5 / Re) keeps it at 1.9 % of rho c^2 (thesis eq. 3.38);
at Re = 0.01 that is c = 283 m/s and mu = 500 Pa s, whose step (acoustic and viscous limits
alike, about 7e-7 s at 10 across) is some 7 times shorter than Re = 0.5's: the creeping runs
are the costly ones.

Each run is measured by tools/die_swell_measure.py (stations --stations, default 0.21 0.23
0.25 m; the steady window: the later half of the frames where all stations are defined):
  envelope  (max y - min y + dx)/W of the slab one dx wide, mean over stations and window;
  filled    the particles' volume per length over W (4 dx slab);
  flux      U / u_bar: the feed's mean velocity over the extrudate's volume-weighted mean
            velocity u_bar in the same 4 dx slabs (a jet carrying the feed's volume flux U W
            at u_bar is U/u_bar wide; the earlier sessions' "from the flux" number).
Per Re, the three finest resolutions give the observed order p and the Richardson-
extrapolated value of each measure (generalised to unequal refinement ratios: p solves
(h3^p - h2^p)/(h2^p - h1^p) = (phi3 - phi2)/(phi2 - phi1), h = W/N, h1 the finest;
phi_ext = phi1 + (phi1 - phi2)/((h2/h1)^p - 1); GCI_fine = 1.25 |phi2 - phi1| / |phi1| /
((h2/h1)^p - 1), Roache 1998, Celik et al. 2008). A sequence that is not monotone, or whose
differences do not shrink (p <= 0), has no extrapolated value, and the output says so; an
order outside [0.5, 4] is flagged as probably not yet in the asymptotic range.

Variants (one thing at a time against the baseline; each adds a suffix to the study's folder):
--wall-floor P (pressure_floor on both die walls, Pa; _floorP), --xsph EPS (0 deletes
[effects.xsph]; _xsphEPS), --delta D (0 deletes [effects.density_diffusion]; _deltaD),
--shifting A (particle shifting, coefficient A, speed U, with [effects.free_surface] at 0.8;
_shiftingA), --artificial-stress EPS (Monaghan's artificial stress from the pressure, Fang
eqs. 38-44, exponent 4; _asEPS), --sound-speed C (m/s, instead of the rule above; _cC), --integrator TYPE
(_TYPE), --smoothing-ratio R (h/dx instead of 1.6, R <= 5/3 so that the five dummy layers
hold the support 3h; _hR: tells whether a trend follows the kernel's width h or the spacing
dx), --viscous-form stress | stress_renormalised ([effects.viscosity] form = "stress", the
stress-free viscous surface of docs/theory.md §5.4, with the velocity gradient of Fang eq. 23 or
renormalised; _stress, _stress_renormalised), --scheme isph (the projection instead of the
equation of state, as cases/die_swell_newtonian_isph_imex.toml has it: the whole pressure each
step, the symmetric gradient, the density relaxation over 2.9 ms, p = 0 on the rows flagged at
0.97; no sound speed, no density diffusion; _isph), with it
--surface-pressure normal_stress (p = n.T.n on the surface rows flagged at 0.97: ISPH's
Dirichlet value instead of 0, [solver] surface_pressure; WCSPH's [effects.surface_pressure]
instead of the equation of state's pressure there; _nstress), --dry-walls omit (WCSPH: the die's wall
particles whose extrapolated pressure is negative, the lip's end face and the outer rows beside
the extrudate, left out of the pressure force, [effects.pressure_gradient] dry_walls = "omit",
docs/theory.md §6; they pull the extrudate back across the lip; _drywalls), --wetted-faces (each
die wall interacts only with the fluid over its wetted face, [[blocks]] wetted_face = [0, +-1]: the
extrudate past the lip's dry end face does not see the wall, docs/theory.md §6.5; _wetted). Variants combine: each given one changes the scene.

Outputs: OUT/convergence[SUFFIX]/re<Re>_n<N>/ (the scene, the vesph output and log, the
measure's files), OUT/convergence[SUFFIX]/convergence[SUFFIX].csv (one row per run),
..._richardson.csv (one row per Re and measure), ..._richardson.txt (the verdicts) and
..._swell.png (swell against dx/W, the extrapolated values at 0, the finite-element band
1.186-1.20 of creeping planar flow). With two or more --re: ..._re_sweep.csv (one row per Re:
each measure at the finest resolution, the spread of the flux swell over the resolutions, its
Richardson value where one exists) and ..._re_sweep.png (the flux swell of every resolution
against Re on a log axis, between the creeping-flow band and the inviscid bound 5/6: a plane
jet from the parabolic feed keeps its momentum flux 1.2 rho U^2 W, so it contracts to 5/6 W
when viscosity no longer acts).

--compare runs nothing: it reads every OUT/convergence*/convergence*.csv (the case and each
variant measured so far; the folders' CSVs hold the runs of their last invocation, so run
--measure-only over all the resolutions of a folder first), prints one table (swell per variant
and resolution) and plots envelope and flux against h/W (the kernel's width) per variant at the first --re in
OUT/convergence_variants.png.

Exit status: 0 when every run was made or tabulated; 1 when a run could not be measured at
all; 2 for bad arguments.
"""
import argparse
import concurrent.futures
import copy
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tomllib

from vesph import REPO as ROOT, tool_command, tool_environment
from vesph.studies.die_swell import fmt, g6, run_scene, write_rows  # shared with the thesis studies

CASE = os.path.join(ROOT, "cases", "die_swell_newtonian.toml")
# Effects of the case that the study's baseline (Morris' Laplacian, walls that pull, no shifting:
# the case of sessions 6-24) does not have; scene() removes them before applying the variants.
BASELINE_REMOVED = ("velocity_gradient", "free_surface", "particle_shifting")
# The variants that give the case's own settings (scene(25, 0.5, CASE_VARIANT, end=the case's
# end) is the case).
CASE_VARIANT = {"viscous_form": "stress_renormalised", "shifting": 1.0, "wetted_faces": True}
# --scheme isph: the projection of the ISPH die (cases/die_swell_newtonian_isph_imex.toml, the
# die's ISPH scene before the normal-stress surface): the whole pressure each step, the symmetric
# gradient (thesis eq. 3.18) in the correction and the right-hand side, the number-density error
# relaxed over 2.9 ms, p = 0 on the rows flagged at 0.97.
ISPH_SOLVER = {"scheme": "isph", "gradient": "symmetric", "carried_pressure": "predictor",
               "density_relaxation_time": 2.9e-3}
ISPH_SURFACE_THRESHOLD = 0.97
RHO, W, U = 1000.0, 0.01, 0.5            # the case's density, die width, feed mean velocity
DIE_INLET, DIE_EXIT = 0.15, 0.2
RE_CASE, C_CASE = 0.5, 40.0              # the case's Reynolds number and sound speed
H_OVER_DX_CASE = 1.6                     # the case's smoothing ratio h/dx
FE_BAND = (1.186, 1.20)                  # finite elements, creeping planar Newtonian flow
ORDER_RANGE = (0.5, 4.0)                 # observed orders outside: not asymptotic (flagged)


def viscosity(re):
    return RHO * W * U / re


def sound_speed(re):
    """The case's c = 40 m/s at Re = 0.5, scaled so that the die's pressure drop (prop. to
    1/Re) stays the same share of rho c^2."""
    return C_CASE * math.sqrt(RE_CASE / re)


def label(re, n):
    return f"re{re:g}_n{n}"


def variant_suffix(v):
    s = ""
    if v.get("wall_floor") is not None:
        s += f"_floor{v['wall_floor']:g}"
    if v.get("xsph") is not None:
        s += f"_xsph{v['xsph']:g}"
    if v.get("delta") is not None:
        s += f"_delta{v['delta']:g}"
    if v.get("shifting"):
        s += f"_shifting{v['shifting']:g}"
    if v.get("artificial_stress"):
        s += f"_as{v['artificial_stress']:g}"
    if v.get("sound_speed") is not None:
        s += f"_c{v['sound_speed']:g}"
    if v.get("integrator"):
        s += f"_{v['integrator']}"
    if v.get("smoothing_ratio") is not None:
        s += f"_h{v['smoothing_ratio']:g}"
    if v.get("viscous_form") in ("stress", "stress_renormalised"):
        s += "_" + v["viscous_form"]
    if v.get("scheme") == "isph":
        s += "_isph"
    if v.get("surface_pressure") == "normal_stress":
        s += "_nstress"
    if v.get("dry_walls") == "omit":
        s += "_drywalls"
    if v.get("wetted_faces"):
        s += "_wetted"
    return s


def scene(n, re, variant=None, end=None, interval=None):
    """The scene dict of the Newtonian die at n particles across and Reynolds number re, with
    the variant's one change (see the module docstring)."""
    v = variant or {}
    with open(CASE, "rb") as fh:
        s = copy.deepcopy(tomllib.load(fh))
    # The geometry at full precision (not rounded): every block must be a whole number of
    # spacings, and W/13 has no short decimal form.
    dx = W / n
    depth = 5 * dx                       # dummy layers / buffer columns >= support 4.8 dx
    s["name"] = label(re, n)
    s["particles"]["spacing"] = dx
    s["domain"]["min"] = [DIE_INLET - depth, s["domain"]["min"][1]]
    fluid, lower, upper = s["blocks"]
    fluid["min"], fluid["max"] = [DIE_INLET, 0.0], [DIE_EXIT, W]
    lower["min"], lower["max"] = [DIE_INLET - depth, -depth], [DIE_EXIT, 0.0]
    upper["min"], upper["max"] = [DIE_INLET - depth, W], [DIE_EXIT, W + depth]
    s["inflow"]["min"], s["inflow"]["max"] = [DIE_INLET - depth, 0.0], [DIE_INLET, W]
    s["fluid"]["viscosity"] = g6(viscosity(re))
    e = s["effects"]
    # The study's baseline is the case as the study began with it (session 6): Morris'
    # Laplacian, every wall particle in the pressure force and seen from everywhere, no
    # shifting. The case now carries the variants --viscous-form stress_renormalised --shifting 1
    # --wetted-faces (issue 35, sessions 25-26); they are taken out here so that every documented
    # variant command keeps the scene it was measured with.
    for key in BASELINE_REMOVED:
        e.pop(key, None)
    for wall in (lower, upper):          # the case's wetted faces (session 26): --wetted-faces
        wall.pop("wetted_face", None)
    e["viscosity"] = {}
    e["pressure_gradient"] = {}
    e["equation_of_state"]["sound_speed"] = g6(v["sound_speed"] if v.get("sound_speed") is not None
                                               else sound_speed(re))
    if v.get("wall_floor") is not None:
        lower["pressure_floor"] = upper["pressure_floor"] = float(v["wall_floor"])
    if v.get("xsph") is not None:
        if v["xsph"] > 0:
            e["xsph"]["epsilon"] = g6(v["xsph"])
        else:
            del e["xsph"]
    if v.get("delta") is not None:
        if v["delta"] > 0:
            e["density_diffusion"]["delta"] = g6(v["delta"])
        else:
            del e["density_diffusion"]
    if v.get("shifting"):
        e.setdefault("free_surface", {"threshold": 0.8})
        e["particle_shifting"] = {"coefficient": g6(v["shifting"]), "speed": U}
    if v.get("artificial_stress"):
        # Monaghan's artificial stress (Fang eqs. 38-44) from the pressure alone (a Newtonian
        # fluid has no elastic stress): a repulsion between particles in tension, where the
        # stress-free surface past the lip carries p = 2 mu dv_n/dn < 0.
        e["artificial_stress"] = {"epsilon": g6(v["artificial_stress"]), "exponent": 4}
    if v.get("integrator"):
        s["integrator"] = {"type": v["integrator"]}
    if v.get("smoothing_ratio") is not None:
        s["particles"]["smoothing_ratio"] = g6(v["smoothing_ratio"])
    if v.get("viscous_form") in ("stress", "stress_renormalised"):
        # The divergence of the full viscous stress mu (grad v + grad v^T): Morris' Laplacian
        # plus the symmetric divergence of mu kappa^T ([effects.viscosity] form = "stress",
        # docs/theory.md §5.4), the stress-free condition of a viscous free surface; kappa by
        # Fang eq. (23) or renormalised (exact for a linear field at the surface).
        e["viscosity"] = {"form": "stress"}
        e["velocity_gradient"] = ({"form": "renormalised"} if v["viscous_form"] == "stress_renormalised" else {})
    if v.get("scheme") == "isph":
        # The projection instead of the equation of state (ISPH_SOLVER above): no density
        # evolution, equation of state or density diffusion (the projection holds the volume);
        # the flagged surface rows are its Dirichlet rows. Everything else (resolution,
        # viscosity, variants) stays.
        for k in ("continuity", "equation_of_state", "density_diffusion"):
            e.pop(k, None)
        e["free_surface"] = {"threshold": ISPH_SURFACE_THRESHOLD}
        e["pressure_gradient"] = {"form": "symmetric"}
        s["solver"] = dict(ISPH_SOLVER)
        if v.get("surface_pressure") == "normal_stress":
            # p = n.T.n on the flagged rows instead of 0 (the viscous normal stress; needs the
            # velocity gradient, which the stress form has already)
            s["solver"]["surface_pressure"] = "normal_stress"
            e.setdefault("velocity_gradient", {"form": "renormalised"})
    if v.get("surface_pressure") == "normal_stress" and v.get("scheme") != "isph":
        # WCSPH: the flagged rows (the ISPH scene's threshold) take p = n.T.n instead of their
        # equation-of-state pressure ([effects.surface_pressure]; T the viscous stress of the
        # velocity gradient): the surface balance without the tension the density would need.
        e.setdefault("free_surface", {})["threshold"] = ISPH_SURFACE_THRESHOLD
        e["surface_pressure"] = {"value": "normal_stress"}
        e.setdefault("velocity_gradient", {"form": "renormalised"})
    if v.get("dry_walls") == "omit":
        # The wall particles whose extrapolated pressure is negative (dry: the lip's end face,
        # the outer rows by the extrudate) out of the pressure force, so that they do not pull
        # the extrudate back across the lip (docs/notes/die_swell.md, session 22).
        e["pressure_gradient"]["dry_walls"] = "omit"
    if v.get("wetted_faces"):
        # Each die wall interacts only with the fluid over its wetted face: the extrudate past
        # the lip's dry end face does not see the wall ([[blocks]] wetted_face, docs/theory.md §6.5).
        lower["wetted_face"] = [0.0, 1.0]
        upper["wetted_face"] = [0.0, -1.0]
    if end is not None:
        s["time"]["end"] = g6(end)
    if interval is not None:
        s["output"]["interval"] = g6(interval)
    return s


# ------------------------------------------------------------------- Richardson extrapolation
def observed_order(across, values, order_range=ORDER_RANGE):
    """Observed order and Richardson extrapolation from the three finest of (across, value)
    pairs (h = 1/across). Returns a dict: n (the three N used, finest first), values (theirs),
    p, extrapolated, gci (relative, fine grid), status ("monotone", "oscillatory", "diverging",
    "unchanged", "too_few", "undefined") and message (a sentence saying what can be read)."""
    pts = sorted(((int(n), float(v)) for n, v in zip(across, values)), key=lambda t: -t[0])
    nan = math.nan
    res = {"n": [t[0] for t in pts[:3]], "values": [t[1] for t in pts[:3]], "p": nan,
           "extrapolated": nan, "gci": nan, "asymptotic": False}
    if len(pts) < 3 or len({t[0] for t in pts[:3]}) < 3:
        res.update(status="too_few", message="fewer than three resolutions: no observed order")
        return res
    (n1, f1), (n2, f2), (n3, f3) = pts[:3]
    if not all(math.isfinite(f) for f in (f1, f2, f3)):
        res.update(status="undefined", message="a resolution has no value: no observed order")
        return res
    e21, e32 = f2 - f1, f3 - f2
    r21, r32 = n1 / n2, n2 / n3           # h2/h1, h3/h2 (> 1)
    if e21 == 0.0 and e32 == 0.0:
        res.update(status="unchanged", extrapolated=f1, gci=0.0, asymptotic=True,
                   message="the three finest values are equal")
        return res
    if e21 == 0.0 or e32 == 0.0 or e32 / e21 < 0.0:
        res.update(status="oscillatory",
                   message=f"not monotone: N = {n3}, {n2}, {n1} give {f3:.4g}, {f2:.4g}, {f1:.4g} "
                           "(the change reverses, or stops and restarts, under refinement); not in the "
                           "asymptotic range, no Richardson value")
        return res
    ratio = e32 / e21
    # R(p) = (h3^p - h2^p)/(h2^p - h1^p) in units of h1: (r21 r32)^p - r21^p over r21^p - 1;
    # increasing in p from 0 (p -> -inf) through ln(r32)/ln(r21) (p -> 0) to infinity.
    def R(p):
        if abs(p) < 1e-12:
            return math.log(r32) / math.log(r21)
        return ((r21 * r32) ** p - r21 ** p) / (r21 ** p - 1.0)

    lo, hi = -40.0, 40.0
    if not (R(lo) < ratio < R(hi)):
        res.update(status="diverging" if ratio <= R(lo) else "monotone",
                   message="the observed order is outside [-40, 40]")
        return res
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if R(mid) < ratio:
            lo = mid
        else:
            hi = mid
    p = 0.5 * (lo + hi)
    res["p"] = p
    if p <= 0.0:
        res.update(status="diverging",
                   message=f"monotone but not converging: the change grows under refinement "
                           f"({f3:.4g} -> {f2:.4g} -> {f1:.4g} for N = {n3}, {n2}, {n1}; observed "
                           f"order {p:.3g} <= 0); no Richardson value")
        return res
    den = r21 ** p - 1.0
    res["extrapolated"] = f1 + (f1 - f2) / den
    res["gci"] = 1.25 * abs(e21) / abs(f1) / den if f1 != 0.0 else nan
    res["asymptotic"] = order_range[0] <= p <= order_range[1]
    msg = (f"monotone: N = {n3}, {n2}, {n1} give {f3:.4g}, {f2:.4g}, {f1:.4g}; observed order "
           f"{p:.3g}, Richardson value {res['extrapolated']:.4g} (GCI {100 * res['gci']:.2g} %)")
    if not res["asymptotic"]:
        msg += (f"; the order lies outside [{order_range[0]:g}, {order_range[1]:g}]: probably not "
                "yet in the asymptotic range, the extrapolated value is not reliable")
    res.update(status="monotone", message=msg)
    return res


# ------------------------------------------------------------------- measuring
def flux_ratio(h5, stations, t0, t1, u_feed=U, die_width=W, window=4.0):
    """(mean, std) over the frames with t0 <= time <= t1 of U / u_bar averaged over the
    stations, u_bar the volume-weighted mean x velocity of the fluid particles in the slab
    x_s - window dx/2 <= x < x_s + window dx/2; nan when a station is empty in every frame."""
    import numpy as np
    from vesph.measure.die_swell import Run

    r = Run(h5)
    try:
        half = 0.5 * window * r.dx
        vals = []
        for k, (_, t) in enumerate(r.frames):
            if t < t0 - 1e-12 or t > t1 + 1e-12:
                continue
            fr = r.read_frame(k, full=True)
            if fr is None:
                continue
            fl = fr["kind"] == 0
            x, u = fr["position"][fl, 0], fr["velocity"][fl, 0]
            vol = fr["volume"][fl] if "volume" in fr else np.ones(int(fl.sum()))
            per = []
            for xs in stations:
                m = (x >= xs - half * (1 + 1e-9)) & (x < xs + half * (1 - 1e-9))
                if np.count_nonzero(m) < 2:
                    per.append(math.nan)
                    continue
                ub = float(np.sum(vol[m] * u[m]) / np.sum(vol[m]))
                per.append(u_feed / ub if ub > 0 else math.nan)
            if all(math.isfinite(q) for q in per):
                vals.append(float(np.mean(per)))
        if not vals:
            return math.nan, math.nan
        return float(np.mean(vals)), float(np.std(vals))
    finally:
        r.close()


def smoothing_length(d, lab, dx):
    """h of the run's scene (its particles.smoothing_ratio times dx; the case's 1.6 when the
    scene is not there)."""
    try:
        with open(os.path.join(d, lab + ".toml"), "rb") as fh:
            return dx * float(tomllib.load(fh)["particles"].get("smoothing_ratio", H_OVER_DX_CASE))
    except (OSError, KeyError, ValueError, tomllib.TOMLDecodeError):
        return dx * H_OVER_DX_CASE


def row_h(r):
    """h (m) of a CSV row; rows written before the h_m column have the case's h = 1.6 dx."""
    h = r.get("h_m")
    return float(h) if h not in (None, "") else H_OVER_DX_CASE * float(r["dx_m"])


def measure_run(d, lab, re, n, stations, rc=None, wall=math.nan, png=True):
    """The study's row of one run (None when it left neither output nor summary)."""
    from vesph.studies.die_swell import extrudate_clusters, run_summary

    h5 = os.path.join(d, lab + ".h5")
    measure_only = rc is None
    js, rc, wall = run_summary(d, rc, wall)
    if measure_only and js is None and not os.path.exists(h5):
        return None
    row = {"label": lab, "Re": re, "across": n, "dx_m": W / n, "h_m": smoothing_length(d, lab, W / n),
           "mu_Pa_s": viscosity(re),
           "exit_status": rc, "status": (js or {}).get("status", ""),
           "end_time_s": (js or {}).get("final_time", math.nan),
           "steps": (js or {}).get("steps", math.nan), "wall_s": wall}
    if js and js.get("status") != "ok" and "message" in js:
        row["message"] = js["message"]
    if not os.path.exists(h5):
        return row
    m = subprocess.run(tool_command("vesph.measure.die_swell") + [
        h5, "--out-dir", d, "--prefix", lab, "--stations", *[f"{x:g}" for x in stations]]
        + ([] if png else ["--no-png"]), capture_output=True, text=True, env=tool_environment())
    sj = os.path.join(d, lab + "_summary.json")
    if m.returncode == 0 and os.path.exists(sj):
        with open(sj) as fh:
            ms = json.load(fh)
        num = lambda v: math.nan if v is None else float(v)  # noqa: E731
        row["envelope"], row["envelope_std"] = num(ms["average"]["mean"]), num(ms["average"]["std"])
        row["filled"], row["filled_std"] = num(ms["filled"]["mean"]), num(ms["filled"]["std"])
        for s in ms["stations"]:
            row[f"envelope_x{s['x_m']:g}"] = num(s["mean"])
        row["frames_used"] = ms["frames_used"]
        t0, t1 = (num(t) for t in ms["time_window_s"])
        row["window_from_s"], row["window_to_s"] = t0, t1
        if math.isfinite(t0):
            row["flux"], row["flux_std"] = flux_ratio(h5, stations, t0, t1)
    else:
        row["message"] = ((m.stderr or m.stdout).strip().splitlines() or [""])[-1]
    try:
        row["clusters"], row["detached"], _ = extrudate_clusters(h5)
    except Exception as ex:   # an unreadable output is reported, not fatal
        row["message"] = str(ex)
    return row


COLUMNS = ["label", "Re", "across", "dx_m", "h_m", "mu_Pa_s", "exit_status", "status", "end_time_s",
           "steps", "wall_s", "envelope", "envelope_std", "filled", "filled_std", "flux",
           "flux_std", "frames_used", "window_from_s", "window_to_s", "clusters", "detached",
           "message"]
MEASURES = ("envelope", "filled", "flux")


def richardson_rows(rows, res_list):
    out = []
    for re in res_list:
        sel = [r for r in rows if r["Re"] == re]
        for q in MEASURES:
            o = observed_order([r["across"] for r in sel], [r.get(q, math.nan) for r in sel])
            out.append({"Re": re, "measure": q, **o})
    return out


def plot(rows, rich, png, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.axhspan(*FE_BAND, color="0.85", label="finite elements, creeping flow (1.186-1.20)")
    marks = {"envelope": "o-", "filled": "s:", "flux": "^--"}
    for re in sorted({r["Re"] for r in rows}, reverse=True):
        sel = sorted((r for r in rows if r["Re"] == re), key=lambda r: r["across"])
        color = None
        for q in MEASURES:
            x = [1.0 / r["across"] for r in sel]
            y = [r.get(q, math.nan) for r in sel]
            err = [r.get(q + "_std", math.nan) for r in sel]
            cont = ax.errorbar(x, y, yerr=[e if math.isfinite(e) else 0.0 for e in err], fmt=marks[q],
                               color=color, capsize=3, label=f"Re = {re:g}: {q} (± std over the window)")
            color = cont.lines[0].get_color()
            o = next((o for o in rich if o["Re"] == re and o["measure"] == q), None)
            if o and math.isfinite(o["extrapolated"]):
                ax.plot([0.0], [o["extrapolated"]], marks[q][0], color=color, mfc="none", ms=9)
    ax.axhline(1.0, color="k", lw=0.6)
    ax.set_xlim(left=0.0)
    ax.set_xlabel("dx / W = 1 / (particles across)  (open markers at 0: Richardson values)")
    ax.set_ylabel("steady swell ratio")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


INVISCID_BOUND = 5.0 / 6.0               # plane jet from a parabolic profile: momentum flux 1.2 U^2 W


def re_sweep_rows(rows, rich):
    """One row per Reynolds number: each measure at the finest resolution that has it (mean and
    std over the steady window), the resolutions measured, and the flux swell's Richardson value
    where the three finest are monotone (the --re sweep's table, issue 35 item 4)."""
    out = []
    for re in sorted({r["Re"] for r in rows}):
        sel = [r for r in rows if r["Re"] == re and math.isfinite(r.get("flux", math.nan))]
        if not sel:
            continue
        fine = max(sel, key=lambda r: r["across"])
        o = next((o for o in rich if o["Re"] == re and o["measure"] == "flux"), None) or {}
        out.append({"Re": re, "across_finest": fine["across"],
                    "resolutions": " ".join(str(r["across"]) for r in sorted(sel, key=lambda r: r["across"])),
                    **{q: fine.get(q, math.nan) for q in ("flux", "flux_std", "envelope",
                                                          "envelope_std", "filled", "filled_std")},
                    "flux_spread": (max(r["flux"] for r in sel) - min(r["flux"] for r in sel)),
                    "flux_richardson": o.get("extrapolated", math.nan),
                    "flux_order": o.get("p", math.nan), "flux_status": o.get("status", "too_few")})
    return out


RE_SWEEP_COLUMNS = ["Re", "across_finest", "resolutions", "flux", "flux_std", "flux_spread", "envelope",
                    "envelope_std", "filled", "filled_std", "flux_richardson", "flux_order", "flux_status"]


def plot_re_sweep(rows, png, title):
    """Swell against Re (log axis): the flux swell of every resolution, the envelope at the
    finest, the creeping-flow finite-element band and the inviscid bound 5/6."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.axhspan(*FE_BAND, color="0.85", label="finite elements, creeping flow (1.186-1.20)")
    ax.axhline(INVISCID_BOUND, color="k", ls="--", lw=0.8,
               label="inviscid bound 5/6 (momentum flux of the parabolic feed)")
    ax.axhline(1.0, color="k", lw=0.5)
    for n in sorted({r["across"] for r in rows}):
        sel = sorted((r for r in rows if r["across"] == n and math.isfinite(r.get("flux", math.nan))),
                     key=lambda r: r["Re"])
        if sel:
            ax.errorbar([r["Re"] for r in sel], [r["flux"] for r in sel],
                        yerr=[r["flux_std"] if math.isfinite(r.get("flux_std", math.nan)) else 0.0 for r in sel],
                        marker="o", capsize=3,
                        label=f"flux swell, {n} across")
    fine = max(r["across"] for r in rows)
    sel = sorted((r for r in rows if r["across"] == fine and math.isfinite(r.get("envelope", math.nan))),
                 key=lambda r: r["Re"])
    if sel:
        ax.plot([r["Re"] for r in sel], [r["envelope"] for r in sel], "s:", color="0.4",
                label=f"envelope swell, {fine} across")
    ax.set_xscale("log")
    ax.set_xlabel("Re = rho W U / mu")
    ax.set_ylabel("steady swell ratio")
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def compare(out, re, png=True):
    """The table and figure of --compare (see the module docstring)."""
    import glob

    series = {}
    for path in sorted(glob.glob(os.path.join(out, "convergence*", "convergence*.csv"))):
        name = os.path.basename(os.path.dirname(path))
        if os.path.basename(path) != name + ".csv":
            continue                      # the _richardson.csv beside it
        with open(path, newline="") as fh:
            rows = [r for r in csv.DictReader(fh) if float(r["Re"]) == re]
        if rows:
            series[name] = sorted(rows, key=row_h)
    if not series:
        print(f"no convergence*.csv with Re = {re:g} under {out}")
        return 1
    num = lambda r, k: float(r[k]) if r.get(k) not in (None, "") else math.nan  # noqa: E731
    print(f"== die swell variants at Re = {re:g} (steady mean +- std over the window)")
    print(f"   {'variant':<34}{'N':>4}{'h/W':>7}{'envelope':>16}{'filled':>9}{'flux':>16}{'wall s':>8}")
    for name, rows in series.items():
        for r in rows:
            print(f"   {name:<34}{int(r['across']):>4}{row_h(r) / W:>7.3f}"
                  f"{num(r, 'envelope'):>9.3f} +-{num(r, 'envelope_std'):.3f}{num(r, 'filled'):>9.3f}"
                  f"{num(r, 'flux'):>9.3f} +-{num(r, 'flux_std'):.3f}{num(r, 'wall_s'):>8.0f}")
    if not png:
        return 0
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, q in zip(axes, ("envelope", "flux")):
        ax.axhspan(*FE_BAND, color="0.85", label="finite elements, creeping flow")
        for name, rows in series.items():
            # against the kernel's width h (the swell follows h, not dx: docs/notes/die_swell.md)
            x = [row_h(r) / W for r in rows]
            ax.errorbar(x, [num(r, q) for r in rows], yerr=[num(r, q + "_std") for r in rows],
                        marker="o", capsize=3, label=name.replace("convergence", "case") or "case")
        ax.set_xlim(left=0.0)
        ax.set_xlabel("h / W")
        ax.set_title(f"{q} swell, Re = {re:g}")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("steady swell ratio")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fn = os.path.join(out, "convergence_variants.png")
    fig.savefig(fn, dpi=120)
    plt.close(fig)
    print(f"wrote {fn}")
    return 0


def main(argv=None):
    from vesph.studies.die_swell import toml_dumps

    ap = argparse.ArgumentParser(prog="die_swell_study.py convergence",
                                 description="the Newtonian die swell under refinement")
    ap.add_argument("--across", type=int, nargs="+", default=[10, 16, 25], metavar="N")
    ap.add_argument("--re", type=float, nargs="+", default=[0.5, 0.01], metavar="RE")
    ap.add_argument("--end", type=float, default=0.35, metavar="T",
                    help="end time, s (default 0.35 s, the case's end time until session 25)")
    ap.add_argument("--interval", type=float, default=0.005, metavar="T",
                    help="output interval, s (default 0.005)")
    ap.add_argument("--stations", type=float, nargs="+", default=[0.21, 0.23, 0.25], metavar="X")
    ap.add_argument("--wall-floor", type=float, default=None, metavar="P")
    ap.add_argument("--xsph", type=float, default=None, metavar="EPS")
    ap.add_argument("--delta", type=float, default=None, metavar="D")
    ap.add_argument("--shifting", type=float, default=0.0, metavar="A")
    ap.add_argument("--artificial-stress", type=float, default=None, metavar="EPS",
                    help="add [effects.artificial_stress] with epsilon EPS (exponent 4; suffix _asEPS)")
    ap.add_argument("--sound-speed", type=float, default=None, metavar="C")
    ap.add_argument("--integrator", default=None, metavar="TYPE")
    ap.add_argument("--viscous-form", choices=["laplacian", "stress", "stress_renormalised"], default=None,
                    help="stress: [effects.viscosity] form = \"stress\" (Morris' Laplacian plus "
                         "the symmetric divergence of mu kappa^T: the stress-free surface); "
                         "stress_renormalised: the same with the renormalised velocity gradient")
    ap.add_argument("--smoothing-ratio", type=float, default=None, metavar="R",
                    help="h/dx instead of the case's 1.6 (the dummy layers stay 5 dx deep: "
                         "R <= 5/3 with the quintic kernel's support 3h)")
    ap.add_argument("--scheme", choices=["wcsph", "isph"], default="wcsph",
                    help="pressure treatment (default wcsph; isph: the projection of "
                         "cases/die_swell_newtonian_isph_imex.toml, suffix _isph)")
    ap.add_argument("--surface-pressure", choices=["zero", "normal_stress"], default=None,
                    help="the pressure of the flagged surface rows (threshold 0.97): ISPH's Dirichlet "
                         "value [solver] surface_pressure, WCSPH's [effects.surface_pressure] (default: "
                         "the equation of state's / ISPH p = 0; normal_stress: p = n.T.n, suffix _nstress)")
    ap.add_argument("--dry-walls", choices=["include", "omit"], default="include",
                    help="WCSPH: omit leaves the die's dry wall particles (negative extrapolated pressure) out "
                         "of the pressure force ([effects.pressure_gradient] dry_walls; suffix _drywalls)")
    ap.add_argument("--wetted-faces", action="store_true",
                    help="each die wall interacts only with the fluid over its wetted face ([[blocks]] wetted_face: "
                         "the lip's end face is dry; suffix _wetted)")
    ap.add_argument("--jobs", type=int, default=1, metavar="J")
    ap.add_argument("--out", default="out/die_swell_study", metavar="DIR")
    ap.add_argument("--vesph", default=os.path.join(ROOT, "build", "vesph"), metavar="PATH")
    ap.add_argument("--dry-run", action="store_true")
    ap.add_argument("--measure-only", action="store_true")
    ap.add_argument("--no-png", action="store_true")
    ap.add_argument("--compare", action="store_true",
                    help="run nothing: tabulate and plot every OUT/convergence* study at the first --re")
    a = ap.parse_args(argv)
    if a.compare:
        return compare(a.out, a.re[0], png=not a.no_png)
    if min(a.across) < 5 or len(set(a.across)) != len(a.across):
        ap.error("--across: distinct resolutions of at least 5 particles across the die")
    if min(a.re) <= 0:
        ap.error("--re must be > 0")
    if any(not (DIE_EXIT < x < 0.3) for x in a.stations):
        ap.error("--stations must lie between the die exit (0.2 m) and the outflow (0.3 m)")
    if a.xsph is not None and not (0.0 <= a.xsph <= 1.0):
        ap.error("--xsph must lie in [0, 1]")
    if a.delta is not None and a.delta < 0 or a.shifting < 0:
        ap.error("--delta and --shifting must be >= 0")
    if a.artificial_stress is not None and not (0.0 < a.artificial_stress <= 1.0):
        ap.error("--artificial-stress must lie in (0, 1]")
    if a.sound_speed is not None and a.sound_speed <= 0:
        ap.error("--sound-speed must be > 0")
    if a.smoothing_ratio is not None and not (0.8 <= a.smoothing_ratio <= 5.0 / 3.0):
        ap.error("--smoothing-ratio must lie in [0.8, 5/3]: the five dummy layers must hold the "
                 "quintic kernel's support 3h")
    if a.scheme == "isph" and (a.sound_speed is not None or a.delta is not None):
        ap.error("--scheme isph has no sound speed or density diffusion: drop --sound-speed, --delta")
    if a.scheme == "isph" and a.dry_walls == "omit":
        ap.error("--dry-walls omit is a WCSPH option (the ISPH projection solves the wall pressures with the fluid's and corrects the velocities through them)")
    if a.wall_floor is not None and not math.isfinite(a.wall_floor):
        ap.error("--wall-floor must be a finite pressure (Pa)")
    if not (a.dry_run or a.measure_only) and not shutil.which(a.vesph) and not os.path.exists(a.vesph):
        ap.error(f"--vesph {a.vesph}: no such executable (build first: see README)")
    variant = {"wall_floor": a.wall_floor, "xsph": a.xsph, "delta": a.delta,
               "shifting": a.shifting, "artificial_stress": a.artificial_stress, "sound_speed": a.sound_speed, "integrator": a.integrator,
               "smoothing_ratio": a.smoothing_ratio, "viscous_form": a.viscous_form,
               "scheme": a.scheme, "surface_pressure": a.surface_pressure, "dry_walls": a.dry_walls,
               "wetted_faces": a.wetted_faces}
    name = "convergence" + variant_suffix(variant)
    sd = os.path.join(a.out, name)
    todo = []
    for re in a.re:
        for n in sorted(a.across):
            lab = label(re, n)
            d = os.path.join(sd, lab)
            os.makedirs(d, exist_ok=True)
            sp = os.path.join(d, lab + ".toml")
            if not a.measure_only:
                with open(sp, "w") as fh:
                    fh.write(f"# die_swell_study.py {name}: Re = {re:g}, {n} across\n")
                    fh.write(toml_dumps(scene(n, re, variant, a.end, a.interval)) + "\n")
            todo.append((re, n, lab, d, sp))
    if a.dry_run:
        for *_, d, sp in todo:
            print(f"{a.vesph} run {sp} -o {d} --quiet")
        return 0
    results = {}
    if not a.measure_only:
        print(f"== {name}: {len(todo)} runs, {a.jobs} at once", flush=True)
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
            futs = {pool.submit(run_scene, sp, d, a.vesph): lab for _, _, lab, d, sp in todo}
            for f in concurrent.futures.as_completed(futs):
                results[futs[f]] = f.result()
                print(f"   {futs[f]}: exit {results[futs[f]][0]}, {results[futs[f]][1]:.0f} s",
                      flush=True)
    status, rows = 0, []
    for re, n, lab, d, _ in todo:
        rc, wall = results.get(lab, (None, math.nan))
        row = measure_run(d, lab, re, n, a.stations, rc, wall, png=not a.no_png)
        if row is None:
            print(f"   {lab}: no output in {d}")
            status = 1
            continue
        rows.append(row)
    rich = richardson_rows(rows, a.re)
    csv_path = os.path.join(sd, name + ".csv")
    write_rows(csv_path, COLUMNS, rows)
    rcsv = os.path.join(sd, name + "_richardson.csv")
    with open(rcsv, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["Re", "measure", "n_fine_to_coarse", "values", "observed_order", "extrapolated",
                    "gci_fine", "asymptotic", "status", "message"])
        for o in rich:
            w.writerow([fmt(o["Re"]), o["measure"], " ".join(map(str, o["n"])),
                        " ".join(fmt(v) for v in o["values"]), fmt(o["p"]), fmt(o["extrapolated"]),
                        fmt(o["gci"]), o["asymptotic"], o["status"], o["message"]])
    print(f"== {name}")
    print(f"   {'label':<14}{'exit':>5}{'wall s':>8}{'envelope':>10}{'std':>7}{'filled':>8}"
          f"{'flux':>8}{'clust':>6}{'det':>5}")
    for r in rows:
        print(f"   {r['label']:<14}{r['exit_status']:5d}{fmt(r.get('wall_s')):>8}"
              f"{fmt(r.get('envelope')):>10.8}{fmt(r.get('envelope_std')):>7.5}"
              f"{fmt(r.get('filled')):>8.6}{fmt(r.get('flux')):>8.6}"
              f"{fmt(r.get('clusters')):>6}{fmt(r.get('detached')):>5}"
              + (f"   ({r['message']})" if r.get("message") else ""))
    txt = os.path.join(sd, name + "_richardson.txt")
    with open(txt, "w") as fh:
        for o in rich:
            line = f"Re = {o['Re']:g}, {o['measure']}: {o['message']}"
            print("   " + line)
            fh.write(line + "\n")
    print(f"wrote {csv_path}, {rcsv}, {txt}")
    if rows and not a.no_png:
        png = os.path.join(sd, name + "_swell.png")
        plot(rows, rich, png, f"die swell, Newtonian: {name}")
        print(f"wrote {png}")
    sweep = re_sweep_rows(rows, rich)
    if len(sweep) >= 2:
        # more than one Re measured: the swell against Re (its table and figure)
        scsv = os.path.join(sd, name + "_re_sweep.csv")
        write_rows(scsv, RE_SWEEP_COLUMNS, sweep)
        print(f"== swell against Re (flux swell at the finest resolution; bounds: creeping "
              f"{FE_BAND[0]:g}-{FE_BAND[1]:g}, inviscid {INVISCID_BOUND:.4g})")
        print(f"   {'Re':>6}{'N':>4}{'flux':>9}{'std':>7}{'spread':>8}{'envelope':>10}{'Richardson':>12}")
        for r in sweep:
            print(f"   {r['Re']:>6g}{r['across_finest']:>4}{r['flux']:>9.4f}{r['flux_std']:>7.3f}"
                  f"{r['flux_spread']:>8.3f}{r['envelope']:>10.4f}{fmt(r['flux_richardson']):>12}")
        print(f"wrote {scsv}")
        if not a.no_png:
            png = os.path.join(sd, name + "_re_sweep.png")
            plot_re_sweep(rows, png, f"die swell against Re, Newtonian: {name}")
            print(f"wrote {png}")
    return status


if __name__ == "__main__":
    sys.exit(main())
