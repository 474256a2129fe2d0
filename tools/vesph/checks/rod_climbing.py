#!/usr/bin/python3
"""Rod climbing (the Weissenberg effect, 3D; docs/validation.md §20): the free-surface height
around a rotating rod against the second-order theory (Joseph & Fosdick 1973).

Usage
-----
    tools/vesph-post rod_climbing_check H5FILE [H5FILE ...] [--frames 4] [--tolerance 0.15]
        [--steady-tolerance 0.1] [--startup-tolerance 0.03] [--until T] [--rest H5FILE] [--void-limit 0.7]
        [--reference couette|surface] [--measure rod|profile] [--report-only] [--csv CSV] [--png PNG]
        [--sweep-csv CSV] [--sweep-png PNG]

The scene (y vertical, gravity along -y): the rod is the wall block of shape "cylinder" with
an angular_velocity (omega about the vertical axis through axis_point), radius a; the container
is the wall block of shape "tube" (inner radius R); the fluid a tube a < r < R. g is the
magnitude of the body force, rho the fluid density; the fluid model from the effects: Newtonian
(fluid.viscosity only), oldroyd_b (eta_p, lambda) or xpp (eta_p, lambda_0b, alpha).

Measurement (below the particle spacing). The fluid is binned in annuli of width dx about the
axis, from a to R, each annulus in angular sectors of arc about 2 dx; the surface height of an
annulus is the mean over its sectors of the highest fluid particle's height (a sector whose top
particle lies over dx/2 below the annulus' median is left out: its surface particle has moved
into the next sector). The surface at the rod is the first annulus, a < r < a + dx; the far
level is the area-weighted mean over R/2 < r < R - dx (the last annulus is left out: the
surface particles next to the container's wall sit lower, a wall effect). (The
column height, sum m_i/rho_i over the annulus' area, is no measure of the surface: a particle's
volume m/rho need not be the space it fills next to a wall, and the first annulus' column does
not follow its top particles.) The measured rise is
    dh = h(a .. a + dx) - h(R/2 .. R - dx),
averaged over the last --frames frames (default 4). With --rest, the same measure of a run of the
same container with the rod at rest is subtracted (each annulus; its frames at the same times,
or its last ones where it ends earlier): the surface particles next to a
dummy-layer wall settle a few per cent of dx below the far level at rest (a = 2 dx: -0.020 dx at
the rod, -0.037 dx at the container's wall; about 10 um at a = 2 and 3 dx; with the dry wall
particles out of the pressure force, [effects.pressure_gradient] dry_walls = "omit", +0.018 dx), the numerical counterpart of a static meniscus,
which an experiment subtracts too. The steady state, two ways: the mean of
those frames against the mean of the --frames before them, their difference below
--steady-tolerance (default 10 %) of |reference|; and the start-up of the flow itself: the
azimuthal velocity of circular Couette flow started from rest with the rod (its ramp_time
followed), v_t = nu0 (v_rr + v_r/r - v/r^2) with v(a) = omega a, v(R) = 0, nu0 = (eta_s +
eta_p)/rho (viscous: a polymer's lambda is short beside the spin-up time (R - a)^2/(pi^2 nu0)),
gives the theory's rise at the time of the first averaged frame; it must have reached
1 - --startup-tolerance (default 3 %) of the steady rise. The spin-up is slow: the far part of a
container R = 8a takes seconds (Newtonian nu0 = 5e-6 m^2/s: 0.87 of the steady rise at t = 1 s,
while the frame-to-frame drift is 2 %); the frames' drift alone does not see it.

Reference (the exact steady surface of a second-order fluid in circular Couette flow between
the rod and the container; docs/validation.md §20). With v(r) = A r + B/r the Couette profile
of a rod of radius a turning at omega in a container of radius R at rest
(A = -omega a^2/(R^2 - a^2), B = omega a^2 R^2/(R^2 - a^2)) and the shear rate
gamma(r) = r d(v/r)/dr = -2B/r^2, the radial momentum balance at the free surface gives

    rho g h'(r) = rho v^2/r - (psi1 + 4 psi2) gamma^2/r,  i.e.
    h(r) = [A^2 r^2/2 + 2 A B ln r - B^2/(2 r^2)]/g + 2 beta B^2/(rho g r^4) + const,

beta = psi1/2 + 2 psi2 the climbing constant (Newtonian 0; Oldroyd-B eta_p lambda, exact at
any Wi in this viscometric flow; XPP at low Wi eta_p lambda_0b (1 - 2 alpha), its psi2/psi1 =
-alpha/2). The theory's dh is the same annulus means of h(r) as the measurement (the profile
varies like r^-4 across the first annulus). For R -> infinity and the point value at r = a,
h(a) - h(inf) = omega^2 (2 beta - rho a^2/2)/(rho g) (Joseph & Fosdick), printed beside it. The
theory has no floor (an infinitely deep fluid): the cases' container floor is free-slip
(slip = "free", a plane of symmetry under which the Couette flow is exact at any depth); a no-slip
floor slows the flow away from the rod (to half the Couette velocity at r = 4.5a in a fluid 7a
deep) and drives a meridional circulation (docs/validation.md §20).

Sanity of the run (no blow-up, no voids): the fluid mass unchanged, the fluid volume sum m/rho
within 5 % of the first frame's, no particle faster than 5 omega a, and the filling of the
interior: the fluid volume in rings 2 dx x 2 dx (radial x vertical) that lie inside the fluid
(a + dx < r < R - dx, dx < y < the column height - 2 dx) over the ring's volume; its minimum
must exceed --void-limit (default 0.7; a lattice without voids fills about 1).

The surface-flow reference, printed beside the theory (--reference surface compares with it):
the same radial balance with the measured azimuthal velocity of the surface particles, v_s(r),
in place of the Couette profile, rho g h' = rho v_s^2/r - 2 beta gamma_s^2/r with
gamma_s = r d(v_s/r)/dr (v_s/r interpolated as a power of r between the rod, where it is omega,
and the annuli), as the same annulus means. It separates what the floor does to the surface velocity from what it
does otherwise (the meridional circulation it drives, whose normal stresses also move the
surface).

The profile measure (--measure profile), free of the rod's annulus: the amplitude k of the
reference's annulus profile (heights above the far level) fitted by least squares to the measured
profile over the annuli from the second (a + dx .. a + 2 dx) to R/2 (with --rest, both from the
surface at rest), k = sum(dh_i t_i)/sum(t_i^2); an exact surface gives k = 1. Why: the first
annulus' surface is the one the walls' contact moves, by a few per cent of dx at rest and
differently under the two wall treatments ([effects.pressure_gradient] dry_walls), and a rest run
is no additive baseline for it (validation.md §20, session 22); from the second annulus out the
surface at rest is flat within 0.003 dx. Its limit: a climbing fluid's elastic term (r^-4) lies
nearly all in the first annulus, so over the fitted annuli a climbing fluid's profile is mostly
the inertial dip, and k measures the whole balance only where the inertial term dominates there
(the rms of the reference over the fitted annuli is printed; a fluid whose two terms cancel there
has none to fit). Pass with it: |k - 1| <= tolerance, steady: k of the frames before within
--steady-tolerance (as a fraction: 0.1 = 0.1 in k).

Pass: |dh - dh_ref| <= tolerance |dh_ref| (default 15 %; dh_ref the theory unless
--reference surface), steady, sane. Newtonian and
Oldroyd-B scenes are checked; an XPP scene's rise is reported against the low-Wi estimate and
only its sanity and steadiness are checked (as with --report-only for any scene).

Several files (e.g. one fluid at several omega): each is checked; --sweep-csv / --sweep-png
write dh against omega^2 with the theory's line.

--csv writes the profile of the (last) file (annulus radii, measured, theoretical and
surface-flow heights relative to the far level, the surface velocity); --png its picture: the particles in the vertical plane through the
axis (|z| < dx), fluid coloured by speed, and h(r) against the theory and the surface-flow
reference.

Exit status 0 pass, 1 fail, 2 usage.
"""

import argparse
import math
import sys

import numpy as np

from vesph.output import Output, ToolError

MASS_DRIFT_LIMIT = 1e-12
VOLUME_DRIFT_LIMIT = 0.05
SPEED_LIMIT = 5.0          # in units of the rod's speed omega a


def _blocks(scene, kind, shape):
    return [b for b in scene.get("blocks", []) if b.get("kind") == kind and b.get("shape") == shape]


def setup(scene, dx, at_rest=False):
    """The rod, container, fluid and gravity of a rod-climbing scene: a dict. at_rest: the rod's
    angular_velocity must be zero (the baseline run of --rest) instead of a turn about y."""
    if int(scene.get("dimension", 2)) != 3:
        raise ValueError("rod_climbing_check is for 3D scenes")
    rods = [b for b in _blocks(scene, "wall", "cylinder") if "angular_velocity" in b]
    if len(rods) != 1:
        raise ValueError("expected one turning wall cylinder (the rod, with angular_velocity)")
    rod = rods[0]
    w = np.array([float(c) for c in rod["angular_velocity"]])
    if at_rest:
        if np.any(w != 0):
            raise ValueError("the rest run's rod must not turn (angular_velocity = [0.0, 0.0, 0.0])")
    elif abs(w[0]) > 1e-12 * abs(w[1]) or abs(w[2]) > 1e-12 * abs(w[1]) or w[1] == 0:
        raise ValueError("the rod must turn about the vertical (y) axis")
    containers = [b for b in _blocks(scene, "wall", "tube") if "angular_velocity" not in b]
    fluids = _blocks(scene, "fluid", "tube")
    if len(containers) != 1 or len(fluids) != 1:
        raise ValueError("expected one wall tube at rest (the container) and one fluid tube")
    g = np.zeros(3)
    for key in ("body_force",):
        eff = scene.get("effects", {}).get(key)
        if eff is not None:
            g += np.array([float(c) for c in eff["acceleration"]])
    if not (g[1] < 0 and abs(g[0]) < 1e-12 * abs(g[1]) and abs(g[2]) < 1e-12 * abs(g[1])):
        raise ValueError("expected gravity along -y (effects.body_force)")
    fluid = scene["fluid"]
    effects = scene.get("effects", {})
    model, beta, note = "newtonian", 0.0, "Newtonian: beta = 0"
    eta_p = lam = 0.0
    if "oldroyd_b" in effects:
        e = effects["oldroyd_b"]
        eta_p, lam = float(e["polymer_viscosity"]), float(e["relaxation_time"])
        model, beta, note = "oldroyd_b", eta_p * lam, "Oldroyd-B: beta = eta_p lambda"
    elif "xpp" in effects:
        e = effects["xpp"]
        lam = float(e["backbone_relaxation_time"])
        eta_p = float(e["polymer_viscosity"]) if "polymer_viscosity" in e else float(e["modulus"]) * lam
        alpha = float(e.get("anisotropy", 0.0))
        model = "xpp"
        beta = eta_p * lam * (1 - 2 * alpha)
        note = "XPP at low Wi: beta = eta_p lambda_0b (1 - 2 alpha)"
    elif any(k in effects for k in ("ucm", "second_order_fluid")):
        raise ValueError("only Newtonian, Oldroyd-B and XPP scenes are measured")
    axis = np.array([float(c) for c in rod["axis_point"]])
    centre = np.array([float(c) for c in fluids[0]["centre"]])
    if abs(axis[0] - centre[0]) > 1e-9 * dx or abs(axis[2] - centre[2]) > 1e-9 * dx:
        raise ValueError("the rod turns about an axis other than the fluid's")
    return {
        "omega": float(w[1]), "a": 0.5 * float(rod["diameter"]), "R": 0.5 * float(containers[0]["inner_diameter"]),
        "axis": np.array([axis[0], axis[2]]), "g": float(-g[1]), "rho": float(fluid["density"]),
        "eta_s": float(fluid.get("viscosity", 0.0)), "eta_p": eta_p, "lam": lam, "model": model,
        "beta": beta, "note": note, "ramp_time": float(rod.get("ramp_time", 0.0)),
        "y0": float(fluids[0]["centre"][1]) - 0.5 * float(fluids[0]["length"]), "depth": float(fluids[0]["length"]),
    }


def couette_height(r, omega, a, R, g, rho, beta):
    """The theory's h(r) + const (m): the second-order fluid's steady surface in circular
    Couette flow (docstring; docs/validation.md §20)."""
    A = -omega * a * a / (R * R - a * a)
    B = omega * a * a * R * R / (R * R - a * a)
    r = np.asarray(r, dtype=float)
    return (A * A * r * r / 2 + 2 * A * B * np.log(r) - B * B / (2 * r * r)) / g + 2 * beta * B * B / (rho * g * r ** 4)


def annulus_mean(f, r1, r2, n=400):
    """The area-weighted mean of f(r) over r1 < r < r2 (midpoint rule in r^2)."""
    s = np.linspace(r1 * r1, r2 * r2, n + 1)
    mid = np.sqrt(0.5 * (s[1:] + s[:-1]))
    return float(np.mean(f(mid)))


def theory_rise(p, dx):
    """(dh of the annulus means, the infinite-container point value h(a) - h(inf)), m."""
    h = lambda r: couette_height(r, p["omega"], p["a"], p["R"], p["g"], p["rho"], p["beta"])  # noqa: E731
    a, R = p["a"], p["R"]
    finite = annulus_mean(h, a, a + dx) - annulus_mean(h, *far_band(p, dx))
    infinite = p["omega"] ** 2 * (2 * p["beta"] - p["rho"] * a * a / 2) / (p["rho"] * p["g"])
    return finite, infinite


def startup_rise(p, dx, times, nodes=400, steps=2000):
    """The theory's rise (annulus means, m) at each of the times of circular Couette flow started
    from rest: v_t = nu0 (v_rr + v_r/r - v/r^2) on a < r < R with v(a) = omega a f(t) (f the rod's
    ramp factor, 1 without a ramp) and v(R) = 0, nu0 = (eta_s + eta_p)/rho, by backward Euler on a
    uniform grid (L-stable: the impulsive start's short waves are damped, which Crank-Nicolson
    would carry), one run through the sorted times with steps steps to the last (each interval
    at least one), and the surface of the same radial balance as couette_height with that v (the
    normal stress 2 beta gamma^2 taken quasi-steady). Returns the rises in the order of times and
    the spin-up time (R - a)^2/(pi^2 nu0), s. At t >> spin-up time the rise is the steady
    theory's to 3e-3 or better."""
    from scipy.linalg import solve_banded
    a, R, omega = p["a"], p["R"], abs(p["omega"])
    nu = (p["eta_s"] + p["eta_p"]) / p["rho"]
    spin_up = (R - a) ** 2 / (math.pi ** 2 * nu) if nu > 0 else math.inf
    r = np.linspace(a, R, nodes + 1)
    ri, dr = r[1:-1], r[1] - r[0]
    lower = nu * (1 / dr ** 2 - 1 / (2 * dr * ri))       # coefficient of v_{i-1}
    upper = nu * (1 / dr ** 2 + 1 / (2 * dr * ri))       # of v_{i+1}
    diag = nu * (-2 / dr ** 2 - 1 / ri ** 2)
    ramp_time = p.get("ramp_time", 0.0)

    def rod(time):
        if ramp_time > 0 and time < ramp_time:
            return omega * a * 0.5 * (1 - math.cos(math.pi * time / ramp_time))
        return omega * a

    def rise(v):
        spin = v / r
        gamma = r * np.gradient(spin, r, edge_order=2)
        slope = (v * v / r - 2 * p["beta"] * gamma * gamma / (p["rho"] * r)) / p["g"]
        h = np.concatenate([[0.0], np.cumsum(0.5 * (slope[1:] + slope[:-1]) * np.diff(r))])
        hfun = lambda x: np.interp(x, r, h)  # noqa: E731
        return annulus_mean(hfun, a, a + dx) - annulus_mean(hfun, *far_band(p, dx))

    order = sorted(range(len(times)), key=lambda k: times[k])
    t_last = max(times) if len(times) else 0.0
    rises = [0.0] * len(times)
    v = np.zeros(nodes + 1)
    t_now = 0.0
    for k in order:
        span = times[k] - t_now
        if span > 0:
            n = max(1, math.ceil(steps * span / t_last))
            dt = span / n
            band = np.zeros((3, nodes - 1))
            band[0, 1:] = -dt * upper[:-1]
            band[1] = 1 - dt * diag
            band[2, :-1] = -dt * lower[1:]
            for j in range(n):
                v[0] = rod(t_now + (j + 1) * dt)
                rhs = v[1:-1].copy()
                rhs[0] += dt * lower[0] * v[0]
                v[1:-1] = solve_banded((1, 1), band, rhs)
            t_now = times[k]
        rises[k] = rise(v)
    return rises, spin_up


def column_heights(r, vol, edges):
    """The column height of each annulus (sum of the volumes in it over its area), m."""
    which = np.searchsorted(edges, r) - 1
    ok = (which >= 0) & (which < len(edges) - 1)
    v = np.bincount(which[ok], weights=vol[ok], minlength=len(edges) - 1)
    return v / (np.pi * (edges[1:] ** 2 - edges[:-1] ** 2))


def surface_heights(r, theta, y, v_theta, edges, dx):
    """The free surface of each annulus, m, and the azimuthal velocity there, m/s: the means
    over the annulus' angular sectors (arcs of about 2 dx at its mid radius) of the highest
    fluid particle in each sector and of its velocity. A sector whose top particle lies more
    than dx/2 below the median of the annulus' sectors (its surface particle moved into the
    next sector) is left out; NaN for an empty annulus."""
    h = np.full(len(edges) - 1, np.nan)
    v = np.full(len(edges) - 1, np.nan)
    which = np.searchsorted(edges, r) - 1
    for i in range(len(edges) - 1):
        sel = np.flatnonzero(which == i)
        if not sel.size:
            continue
        ns = max(1, int(round(np.pi * (edges[i] + edges[i + 1]) / (2 * dx))))
        sector = np.minimum((theta[sel] + np.pi) * (ns / (2 * np.pi)), ns - 1).astype(int)
        order = np.lexsort((y[sel], sector))            # by sector, then height
        last = np.flatnonzero(np.r_[sector[order][1:] != sector[order][:-1], True])
        top = sel[order[last]]
        keep = y[top] > np.median(y[top]) - 0.5 * dx
        h[i] = float(np.mean(y[top[keep]]))
        v[i] = float(np.mean(v_theta[top[keep]]))
    return h, v


def band_mean(values, edges, r1, r2):
    """The area-weighted mean of per-annulus values over the annuli inside r1 <= r <= r2."""
    area = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    sel = (edges[:-1] >= r1 - 1e-9 * (r2 - r1)) & (edges[1:] <= r2 + 1e-9 * (r2 - r1)) & np.isfinite(values)
    return float(np.sum(values[sel] * area[sel]) / np.sum(area[sel]))


def far_band(p, dx):
    """The far level's radii: R/2 .. R - dx (the last annulus, next to the container's wall,
    is left out: its surface particles sit lower, as next to any wall)."""
    return 0.5 * p["R"], p["R"] - dx


def measure_frame(g, p, dx):
    """The measurements of one frame: a dict (surface heights, rise, sanity figures)."""
    fl = g["kind"] == 0
    x = g["position"][fl]
    d = np.stack([x[:, 0] - p["axis"][0], x[:, 2] - p["axis"][1]], axis=1)
    r = np.hypot(d[:, 0], d[:, 1])
    theta = np.arctan2(d[:, 1], d[:, 0])
    y = x[:, 1] - p["y0"]
    vel = g["velocity"][fl]
    # azimuthal velocity in the rod's sense of rotation (omega about +y: e_theta = (z, 0, -x)/r)
    v_theta = math.copysign(1.0, p["omega"]) * (vel[:, 0] * d[:, 1] - vel[:, 2] * d[:, 0]) / np.maximum(r, 1e-300)
    vol = g["mass"][fl] / g["density"][fl]
    a, R = p["a"], p["R"]
    n = max(1, int(round((R - a) / dx)))
    edges = a + (R - a) * np.arange(n + 1) / n
    h, v_surf = surface_heights(r, theta, y, v_theta, edges, dx)
    column = column_heights(r, vol, edges)
    h_far = band_mean(h, edges, *far_band(p, dx))
    speed = np.linalg.norm(vel, axis=1)
    # Filling of the interior: rings 2 dx x 2 dx inside the fluid.
    re = np.arange(a + dx, R - dx + 1e-9 * dx, 2 * dx)
    depth = float(np.nanmedian(column))
    ye = np.arange(dx, depth - 2 * dx + 1e-9 * dx, 2 * dx)
    fill = 1.0
    if len(re) > 1 and len(ye) > 1:
        hist, _, _ = np.histogram2d(r, y, bins=(re, ye), weights=vol)
        cell = np.pi * (re[1:] ** 2 - re[:-1] ** 2)[:, None] * np.diff(ye)[None, :]
        fill = float((hist / cell).min())
    return {"edges": edges, "h": h, "v_surf": v_surf, "h_far": h_far, "rise": float(h[0] - h_far),
            "mass": float(np.sum(g["mass"][fl], dtype=np.float64)), "volume": float(np.sum(vol)),
            "max_speed": float(speed.max()) if speed.size else 0.0, "fill": fill}


def surface_flow_profile(edges, v_surf, p, dx):
    """The surface that the radial balance of the theory gives with the measured surface
    velocity v_s(r) in place of the Couette profile: the annulus means (m, relative to the far
    band; NaN for an empty annulus) of the h(r) with
        rho g h' = rho v_s^2/r - 2 beta gamma_s^2/r,  gamma_s = r d(v_s/r)/dr
    (beta's normal stress taken as psi1 = 2 beta, psi2 = 0: exact for Oldroyd-B). The angular
    velocity v_s/r is interpolated as a power of r between the rod's (omega, no slip at r = a)
    and the annuli's mid radii (exact for the potential vortex), on a grid of dx/200."""
    mid = 0.5 * (edges[1:] + edges[:-1])
    ok = np.isfinite(v_surf)
    nodes_r = np.concatenate([[p["a"]], mid[ok]])
    spin = np.concatenate([[abs(p["omega"])], v_surf[ok] / mid[ok]])
    spin = np.maximum(spin, 1e-9 * abs(p["omega"]))       # a power law needs spin > 0
    r = np.linspace(p["a"], edges[-1], int(round(200 * (edges[-1] - p["a"]) / dx)) + 1)
    w = np.exp(np.interp(np.log(r), np.log(nodes_r), np.log(spin)))
    gamma = r * np.gradient(w, r, edge_order=2)
    slope = ((w * r) ** 2 / r - 2 * p["beta"] * gamma * gamma / (p["rho"] * r)) / p["g"]
    h = np.concatenate([[0.0], np.cumsum(0.5 * (slope[1:] + slope[:-1]) * np.diff(r))])
    means = np.full(len(mid), np.nan)
    for i in range(len(mid)):
        sel = (r >= edges[i]) & (r <= edges[i + 1])
        if ok[i] and sel.sum() > 1:
            means[i] = float(np.sum(h[sel] * r[sel]) / np.sum(r[sel]))
    return means - band_mean(means, edges, *far_band(p, dx))


def profile_annuli(edges, p):
    """The annuli of the profile measure (--measure profile): from the second (a + dx .. a + 2 dx)
    to the last whose outer radius is at most R/2, where the far band begins. The first annulus
    is left out: its surface is the one the walls' contact moves (a dummy layer holds it some
    0.02 dx low at rest, the dry walls 0.01-0.02 dx high), while from the second annulus out the
    surface at rest is flat within 0.003 dx under either wall treatment (validation.md §20)."""
    half = 0.5 * p["R"]
    return np.flatnonzero((np.arange(len(edges) - 1) >= 1) & (edges[1:] <= half * (1 + 1e-9)))


def profile_amplitude(measured, reference, sel):
    """The least-squares amplitude k of reference (per-annulus heights above the far level) in
    measured over the annuli sel: k = sum(m t)/sum(t t) over the finite ones, and the rms of
    the reference and of the residual m - k t there (m). NaN when the reference vanishes there."""
    m, t = np.asarray(measured, float)[sel], np.asarray(reference, float)[sel]
    ok = np.isfinite(m) & np.isfinite(t)
    m, t = m[ok], t[ok]
    tt = float(np.dot(t, t))
    if not ok.any() or tt <= 0:
        return math.nan, 0.0, math.nan
    k = float(np.dot(m, t)) / tt
    return k, math.sqrt(tt / len(t)), float(np.sqrt(np.mean((m - k * t) ** 2)))


FRAME_FIELDS = ("kind", "position", "velocity", "mass", "density")


def _measured_frames(h5, p, dx, until=None):
    """measure_frame of every frame of an open output (to its last frame at or before until, s,
    when given), each with its frame name and time."""
    rows = []
    for k, (name, t) in enumerate(h5.frames):
        if until is not None and t > until * (1 + 1e-9):
            break
        m = measure_frame(h5.read(k, FRAME_FIELDS), p, dx)
        m.update(frame=name, time=t)
        rows.append(m)
    return rows


def _geometry(p, dx):
    """What a rest run must share with the run it is the baseline of (--rest)."""
    return (dx, p["a"], p["R"], p["y0"], p["depth"])


def rest_baseline(path):
    """The surface of the same container with the rod at rest (--rest): each frame's height of
    each annulus above the far level, m (rows: frames; the first column is the rise at the rod),
    the frames' times, and the geometry to match (dx, a, R, the fluid's bottom and depth).
    Raises ValueError for a run that is no rest run."""
    h5 = Output(path)
    with h5:
        dx = h5.dx
        p = setup(h5.scene, dx, at_rest=True)
        if len(h5.frames) < 2:
            raise ValueError(f"{path}: the rest run has {len(h5.frames)} frame(s); it needs frames after the first")
        rows = _measured_frames(h5, p, dx)
    profiles = np.array([m["h"] - m["h_far"] for m in rows])
    return profiles, [m["time"] for m in rows], _geometry(p, dx)


def _rest_frames(rest_times, times):
    """Indices of the rest run's frames at the given times (each within 1e-9 s), or, where it
    lacks one of them, its last len(times) frames (a rest run shorter than the run: settled)."""
    idx = [next((k for k, t in enumerate(rest_times) if abs(t - u) <= 1e-9 * max(1.0, abs(u))), None) for u in times]
    if all(k is not None for k in idx):
        return idx
    return list(range(max(1, len(rest_times) - len(times)), len(rest_times)))


def check_file(path, frames_avg=4, tolerance=0.15, steady_tolerance=0.1, startup_tolerance=0.03, void_limit=0.7,
               report_only=False, csv=None, png=None, reference_kind="couette", out=sys.stdout, err=sys.stderr,
               until=None, rest=None, measure="rod"):
    """Check one output; returns (status, summary dict or None). until (s): judge the run as if it
    had ended at its last frame at or before that time (the frames after it are not read). rest:
    rest_baseline()'s result for the same container, subtracted from the surface (the rise is then
    measured from the surface at rest, as an experiment measures it from the static meniscus).
    measure: "rod" compares the rise at the rod (the first annulus) with the reference, "profile"
    the amplitude of the reference's profile fitted to the measured one over profile_annuli
    (the first annulus left out) with 1."""
    try:
        h5 = Output(path)
    except ToolError as e:
        print(f"FAIL: {e}", file=err)
        return 1, None, []
    problems = []
    with h5:
        dx = h5.dx
        try:
            p = setup(h5.scene, dx)
        except (ValueError, KeyError, TypeError) as e:
            print(f"FAIL: {path}: {e}", file=err)
            return 1, None, []
        rows = _measured_frames(h5, p, dx, until)
        theory, infinite = theory_rise(p, dx)
        a, R, omega = p["a"], p["R"], p["omega"]
        wi = p["lam"] * abs(omega)
        print(f"file: {path}\n{p['model']}: a = {a:.6g} m  R = {R:.6g} m (R/a = {R / a:.3g})  omega = {omega:.6g} rad/s"
              f"  g = {p['g']:.6g} m/s^2  rho = {p['rho']:.6g} kg/m^3  dx = {dx:.6g} m\n"
              f"Fr = omega^2 a/g = {omega * omega * a / p['g']:.4g}  Re = rho omega a^2/eta0 = "
              f"{p['rho'] * abs(omega) * a * a / max(p['eta_s'] + p['eta_p'], 1e-300):.4g}  Wi = lambda omega = {wi:.4g}"
              f"  beta = {p['beta']:.6g} Pa s^2 ({p['note']})", file=out)
        print(f"{'frame':>8} {'time [s]':>10} {'rise [m]':>12} {'rise [dx]':>10} {'far level [m]':>14}"
              f" {'vol drift':>10} {'max|v|/(wa)':>12} {'min fill':>9}", file=out)
        m0, v0 = rows[0]["mass"], rows[0]["volume"]
        for m in rows:
            print(f"{m['frame']:>8} {m['time']:10.5g} {m['rise']:12.5g} {m['rise'] / dx:10.4f} {m['h_far']:14.6g}"
                  f" {m['volume'] / v0 - 1:10.2e} {m['max_speed'] / (abs(omega) * a):12.4g} {m['fill']:9.3f}", file=out)
            if abs(m["mass"] / m0 - 1) > MASS_DRIFT_LIMIT:
                problems.append(f"frame {m['frame']}: fluid mass drift {m['mass'] / m0 - 1:.3e}")
            if abs(m["volume"] / v0 - 1) > VOLUME_DRIFT_LIMIT:
                problems.append(f"frame {m['frame']}: fluid volume changed by {100 * (m['volume'] / v0 - 1):.3g} %")
            if not m["max_speed"] <= SPEED_LIMIT * abs(omega) * a:
                problems.append(f"frame {m['frame']}: a particle at {m['max_speed']:.4g} m/s > {SPEED_LIMIT:g} omega a")
            if m["time"] > 0 and not m["fill"] > void_limit:
                problems.append(f"frame {m['frame']}: interior filling {m['fill']:.3f} <= {void_limit:g} (a void)")
        n = min(frames_avg, (len(rows) - 1) // 2)
        if n < 1:
            print(f"FAIL: {path}: {len(rows)} frames; need at least 3 to judge the steady state", file=err)
            return 1, None, []
        last = rows[-n:]
        before = rows[-2 * n:-n]
        rise = float(np.mean([m["rise"] for m in last]))
        drift = rise - float(np.mean([m["rise"] for m in before]))
        edges = rows[-1]["edges"]
        # The profiles: time means of the last frames, relative to the far level.
        prof = np.nanmean([m["h"] - m["h_far"] for m in last], axis=0)
        prof_before = np.nanmean([m["h"] - m["h_far"] for m in before], axis=0)
        raw_rise = rise
        if rest is not None:
            rest_profiles, rest_all_times, rest_geometry = rest
            chosen = _rest_frames(rest_all_times, [m["time"] for m in last])
            rest_prof = np.nanmean(rest_profiles[chosen], axis=0)
            rest_times = [rest_all_times[k] for k in chosen]
            geometry = _geometry(p, dx)
            if len(rest_prof) != len(prof) or any(abs(u - v) > 1e-9 * max(abs(u), abs(v), dx)
                                                  for u, v in zip(geometry, rest_geometry)):
                print(f"FAIL: {path}: the rest run is not this container (dx, a, R, fluid bottom and depth "
                      f"{rest_geometry} against {geometry})", file=err)
                return 1, None, []
            rise -= float(rest_prof[0])
            prof = prof - rest_prof
            prof_before = prof_before - rest_prof
        v_surf = np.nanmean([m["v_surf"] for m in last], axis=0)
        surface_ref = surface_flow_profile(edges, v_surf, p, dx)
        surface_rise = float(surface_ref[0])
        reference = theory if reference_kind == "couette" else surface_rise
        lo, hi = far_band(p, dx)
        hfun = lambda r: couette_height(r, omega, a, R, p["g"], p["rho"], p["beta"])  # noqa: E731
        far_th = annulus_mean(hfun, lo, hi)
        th = np.array([annulus_mean(hfun, edges[i], edges[i + 1]) - far_th for i in range(len(edges) - 1)])
        # The profile measure: the reference's annulus profile fitted to the measured one away
        # from the rod's annulus (profile_annuli).
        fit_sel = profile_annuli(edges, p)
        fit_ref = th if reference_kind == "couette" else surface_ref
        amplitude, fit_scale, fit_residual = profile_amplitude(prof, fit_ref, fit_sel)
        amplitude_before = profile_amplitude(prof_before, fit_ref, fit_sel)[0]
        if measure == "profile":
            if not math.isfinite(amplitude):
                print(f"FAIL: {path}: no annulus between a + dx and R/2 to fit the profile in (R/a = {R / a:.3g},"
                      f" dx = {dx:.4g} m)", file=err)
                return 1, None, []
            error = amplitude - 1
            drift_fraction = amplitude - amplitude_before
        else:
            scale = max(abs(reference), 1e-300)
            error = (rise - reference) / scale
            drift_fraction = drift / scale
        steady = abs(drift_fraction) <= steady_tolerance
        check = p["model"] != "xpp" and not report_only
        ok = abs(error) <= tolerance
        print(f"rise at the rod (annulus {a:.4g}..{a + dx:.4g} m) above the far level ({lo:.4g}..{hi:.4g} m), mean of the"
              f" last {n} frames (t = {last[0]['time']:.4g}..{last[-1]['time']:.4g} s): {raw_rise:.5g} m ="
              f" {raw_rise / dx:.4f} dx = {raw_rise / a:.4g} a", file=out)
        if rest is not None:
            print(f"at rest (the same container with the rod at rest, t = {rest_times[0]:.4g}..{rest_times[-1]:.4g} s):"
                  f" {rest_prof[0]:.5g} m = {rest_prof[0] / dx:.4f} dx; the rise from the surface at rest"
                  f" {rise:.5g} m = {rise / dx:.4f} dx (compared below)", file=out)
        print(f"theory (second order, Couette profile of the container, same annuli): {theory:.5g} m = {theory / dx:.4f} dx;"
              f" infinite container at r = a: {infinite:.5g} m; measured/theory = {rise / theory if theory else math.nan:.3f}",
              file=out)
        print(f"surface-flow reference (the same balance with the measured surface velocity, "
              f"{100 * v_surf[0] / (abs(omega) * a):.3g} % of omega a in the first annulus): {surface_rise:.5g} m ="
              f" {surface_rise / dx:.4f} dx; measured/reference = {rise / surface_rise if surface_rise else math.nan:.3f}",
              file=out)
        if fit_sel.size:
            print(f"profile (the {reference_kind} reference's annulus profile fitted to the measured one over annuli"
                  f" {fit_sel[0] + 1}..{fit_sel[-1] + 1}, r = {edges[fit_sel[0]]:.4g}..{edges[fit_sel[-1] + 1]:.4g} m,"
                  f" the rod's annulus left out; the reference there rms {fit_scale / dx:.4f} dx): amplitude"
                  f" {amplitude:.3f} (the frames before {amplitude_before:.3f}), residual rms {fit_residual / dx:.4f} dx",
                  file=out)
        print(f"{'amplitude ' if measure == 'profile' else ''}error {100 * error:+.3g} % of the {reference_kind} reference"
              f"{' profile' if measure == 'profile' else ''} (pass within {100 * tolerance:g} %)"
              f"{'' if check else ' [reported only]'}: {'ok' if ok else 'FAIL' if check else 'outside'}", file=out)
        if measure == "profile":
            print(f"steady: the amplitude of the {n} frames before differs by {drift_fraction:.3g}"
                  f" (within {steady_tolerance:g}): {'ok' if steady else 'FAIL'}", file=out)
        else:
            print(f"steady: the mean of the {n} frames before differs by {drift:.3g} m = {100 * drift_fraction:.3g} % of"
                  f" the reference (within {100 * steady_tolerance:g} %): {'ok' if steady else 'FAIL'}", file=out)
        # The flow's own approach to its steady state (docstring): the start-up of Couette flow.
        startups, spin_up = startup_rise(p, dx, [m["time"] for m in last])
        reached = startups[0] / theory if theory else math.nan
        started = abs(1 - reached) <= startup_tolerance
        startup_mean = float(np.mean(startups))
        print(f"start-up: Couette flow started from rest with the rod (nu0 = {(p['eta_s'] + p['eta_p']) / p['rho']:.4g} m^2/s,"
              f" spin-up time (R - a)^2/(pi^2 nu0) = {spin_up:.4g} s) has {reached:.3f} of its steady rise at"
              f" t = {last[0]['time']:.4g} s (within {100 * startup_tolerance:g} %): {'ok' if started else 'FAIL'};"
              f" its rise over the same frames {startup_mean:.5g} m, measured/that = "
              f"{rise / startup_mean if startup_mean else math.nan:.3f}", file=out)
        if not started:
            problems.append(f"not steady: the start-up of the Couette flow has {reached:.3f} of its steady rise at "
                            f"t = {last[0]['time']:.4g} s (spin-up time {spin_up:.3g} s: run longer, or raise "
                            f"--startup-tolerance)")
        print(f"sanity: mass drift {rows[-1]['mass'] / m0 - 1:.2e}, volume {100 * (rows[-1]['volume'] / v0 - 1):+.3g} %,"
              f" max speed {max(m['max_speed'] for m in rows) / (abs(omega) * a):.3g} omega a,"
              f" least interior filling {min(m['fill'] for m in rows[1:]) if len(rows) > 1 else 1.0:.3f}"
              f" (pass above {void_limit:g})", file=out)
        if check and not ok:
            if measure == "profile":
                problems.append(f"profile amplitude {amplitude:.3f} is {100 * error:+.3g} % off the {reference_kind} reference")
            else:
                problems.append(f"rise {rise:.4g} m is {100 * error:+.3g} % off the {reference_kind} reference's"
                                f" {reference:.4g} m")
        if not steady:
            if measure == "profile":
                problems.append(f"not steady: the profile amplitude changed by {drift_fraction:.3g}")
            else:
                problems.append(f"not steady: the rise changed by {drift:.3g} m ({100 * drift_fraction:.3g} % of the"
                                f" reference)")
        if csv:
            with open(csv, "w") as fh:
                fh.write("r_inner_m,r_outer_m,r_mid_m,h_measured_m,h_theory_m,h_surface_flow_m,v_surface_m_s\n")
                for i in range(len(edges) - 1):
                    fh.write(f"{edges[i]:.9g},{edges[i + 1]:.9g},{0.5 * (edges[i] + edges[i + 1]):.9g},"
                             f"{prof[i]:.9g},{th[i]:.9g},{surface_ref[i]:.9g},{v_surf[i]:.9g}\n")
            print(f"csv: {csv}", file=out)
        if png:
            _picture(h5, p, dx, edges, prof, hfun, far_th, surface_ref, png)
            print(f"png: {png}", file=out)
    summary = {"path": path, "omega": omega, "wi": wi, "rise": rise, "theory": theory, "infinite": infinite,
               "surface": surface_rise,
               "model": p["model"], "dx": dx, "a": a, "drift": drift, "raw_rise": raw_rise,
               "profile_amplitude": amplitude}
    return (1 if problems else 0), summary, problems


def _picture(h5, p, dx, edges, prof, hfun, far_th, surface_ref, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    k = len(h5.frames) - 1
    g = h5.read(k, ("kind", "position", "velocity"))
    x = g["position"]
    sl = np.abs(x[:, 2] - p["axis"][1]) < dx
    fl = sl & (g["kind"] == 0)
    wl = sl & (g["kind"] != 0)
    a, R = p["a"], p["R"]
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.2), gridspec_kw={"width_ratios": [1.6, 1]})
    ax.scatter(x[wl, 0] / a, (x[wl, 1] - p["y0"]) / a, s=2, c="0.6", lw=0)
    sp = np.linalg.norm(g["velocity"][fl], axis=1) / (abs(p["omega"]) * a)
    sc = ax.scatter(x[fl, 0] / a, (x[fl, 1] - p["y0"]) / a, s=3, c=sp, cmap="viridis", lw=0, vmin=0, vmax=1)
    fig.colorbar(sc, ax=ax, label="|v| / (omega a)")
    ax.set_aspect("equal")
    ax.set_xlabel("x / a")
    ax.set_ylabel("y / a")
    ax.set_title(f"{h5.name}: particles with |z| < dx, t = {h5.frames[k][1]:g} s")
    rr = np.linspace(a, R, 300)
    mid = 0.5 * (edges[1:] + edges[:-1])
    bx.plot(rr / a, (hfun(rr) - far_th) / dx, "k-", label="second-order theory (point values)")
    th = [annulus_mean(hfun, edges[i], edges[i + 1]) - far_th for i in range(len(edges) - 1)]
    bx.plot(mid / a, np.array(th) / dx, "k+", label="theory, annulus means")
    bx.plot(mid / a, surface_ref / dx, "x--", color="tab:blue", lw=0.8, label="with the measured surface velocity")
    bx.plot(mid / a, prof / dx, "o", mfc="none", color="tab:red", label="measured (top particles)")
    bx.axhline(0, color="0.7", lw=0.8)
    bx.set_xlabel("r / a")
    bx.set_ylabel("h(r) - h(far)  [dx]")
    lo, hi = far_band(p, dx)
    bx.set_title(f"surface height (far: {lo / a:g} a < r < {hi / a:g} a)")
    bx.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=90)
    plt.close(fig)


def _sweep(summaries, csv, png, out, from_rest=False):
    summaries = sorted(summaries, key=lambda s: abs(s["omega"]))
    print(f"{'omega [rad/s]':>14} {'Wi':>8} {'omega^2':>10} {'rise [m]':>12} {'theory [m]':>12} {'rise/theory':>12}",
          file=out)
    for s in summaries:
        print(f"{s['omega']:14.6g} {s['wi']:8.4g} {s['omega'] ** 2:10.5g} {s['rise']:12.5g} {s['theory']:12.5g}"
              f" {s['rise'] / s['theory'] if s['theory'] else float('nan'):12.4g}", file=out)
    if csv:
        with open(csv, "w") as fh:
            # rise_m: from the surface at rest with --rest (rise_above_far_m without it: the same)
            fh.write("file,model,omega_rad_s,wi,rise_m,theory_m,infinite_m,rise_above_far_m\n")
            for s in summaries:
                fh.write(f"{s['path']},{s['model']},{s['omega']:.9g},{s['wi']:.6g},{s['rise']:.9g},{s['theory']:.9g},"
                         f"{s['infinite']:.9g},{s['raw_rise']:.9g}\n")
        print(f"sweep csv: {csv}", file=out)
    if png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 4.2))
        for model in sorted({s["model"] for s in summaries}):
            ss = [s for s in summaries if s["model"] == model]
            w2 = np.array([s["omega"] ** 2 for s in ss])
            dx = ss[0]["dx"]
            ax.plot(w2, [s["rise"] / dx for s in ss], "o-", label=f"{model}: measured")
            line = np.linspace(0, w2.max() * 1.05, 50)
            slope = ss[0]["theory"] / ss[0]["omega"] ** 2
            ax.plot(line, slope * line / dx, "--", label=f"{model}: second-order theory")
            for s in ss:
                ax.annotate(f"Wi={s['wi']:.2g}", (s["omega"] ** 2, s["rise"] / dx), fontsize=7,
                            textcoords="offset points", xytext=(4, -10))
        ax.axhline(0, color="0.7", lw=0.8)
        ax.set_xlabel("omega^2  [rad^2/s^2]")
        ax.set_ylabel("h(rod) - h(far)  [dx]" + (", from the surface at rest" if from_rest else ""))
        ax.set_title("rise at the rod against omega^2")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(png, dpi=90)
        plt.close(fig)
        print(f"sweep png: {png}", file=out)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="rod_climbing_check",
                                 description="Free-surface height at a rotating rod against the second-order theory.")
    ap.add_argument("h5files", metavar="H5FILE", nargs="+")
    ap.add_argument("--frames", type=int, default=4, help="frames averaged at the end (default 4)")
    ap.add_argument("--tolerance", type=float, default=0.15, help="fraction of the theory's rise (default 0.15)")
    ap.add_argument("--steady-tolerance", type=float, default=0.1,
                    help="change between the last two groups of frames, fraction of the theory (default 0.1)")
    ap.add_argument("--startup-tolerance", type=float, default=0.03,
                    help="the Couette start-up's rise at the averaged frames against its steady rise (default 0.03)")
    ap.add_argument("--until", type=float, metavar="T",
                    help="judge each run as if it had ended at its last frame at or before T s (e.g. a plateau "
                         "before a late drift; default: the whole run)")
    ap.add_argument("--rest", metavar="H5FILE",
                    help="the same container with the rod at rest: its surface (the mean of its frames at the times "
                         "averaged, or of its last ones where it has not all of them) is the baseline the rise is measured from, as an experiment measures from the static "
                         "meniscus (the walls' contact with the surface moves the first annulus by a few per cent "
                         "of dx: docs/validation.md §20)")
    ap.add_argument("--void-limit", type=float, default=0.7, help="least interior filling (default 0.7)")
    ap.add_argument("--reference", choices=("couette", "surface"), default="couette",
                    help="compare with the Couette-profile theory (default) or the surface-flow reference")
    ap.add_argument("--measure", choices=("rod", "profile"), default="rod",
                    help="what is compared: the rise at the rod, the first annulus (default), or the amplitude of "
                         "the reference's profile fitted over the second annulus to R/2 (the rod's annulus, which the "
                         "walls' contact moves, left out)")
    ap.add_argument("--report-only", action="store_true", help="do not compare with the theory (sanity and steadiness only)")
    ap.add_argument("--csv", metavar="CSV", help="the profile of the last file")
    ap.add_argument("--png", metavar="PNG", help="section and profile of the last file")
    ap.add_argument("--sweep-csv", metavar="CSV", help="rise against omega of all files")
    ap.add_argument("--sweep-png", metavar="PNG", help="rise against omega^2 of all files")
    a = ap.parse_args(argv)
    if a.frames < 1:
        ap.error("--frames must be at least 1")
    if a.until is not None and not a.until > 0:
        ap.error("--until must be a time after the start, s")
    status, summaries, problems = 0, [], []
    rest = None
    if a.rest:
        try:
            rest = rest_baseline(a.rest)
        except (ToolError, ValueError, KeyError, TypeError) as e:
            print(f"FAIL: --rest {a.rest}: {e}", file=sys.stderr)
            print("RESULT: FAIL")
            return 1
    for i, path in enumerate(a.h5files):
        last = i == len(a.h5files) - 1
        res = check_file(path, a.frames, a.tolerance, a.steady_tolerance, a.startup_tolerance, a.void_limit,
                         a.report_only, a.csv if last else None, a.png if last else None, a.reference,
                         until=a.until, rest=rest, measure=a.measure)
        if res[1] is None:
            status = 1
            continue
        st, summary, probs = res
        status = max(status, st)
        summaries.append(summary)
        problems += [f"{path}: {q}" for q in probs]
    if len(summaries) > 1 or a.sweep_csv or a.sweep_png:
        _sweep(summaries, a.sweep_csv, a.sweep_png, sys.stdout, from_rest=rest is not None)
    for q in problems:
        print(f"FAIL: {q}", file=sys.stderr)
    print("RESULT: " + ("FAIL" if status else "PASS"))
    return status


if __name__ == "__main__":
    sys.exit(main())
