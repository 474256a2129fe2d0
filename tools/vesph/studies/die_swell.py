#!/usr/bin/python3
"""Run the die-swell studies of the seed thesis (Ch. 4) with vesph and tabulate them: one
command per study, each run a scene derived from cases/die_swell_second_order_fluid.toml.

Usage
-----
    /usr/bin/python3 tools/die_swell_study.py STUDY [STUDY ...]
        [--across N] [--scheme wcsph|isph] [--shifting A] [--room R] [--wall-floor P]
        [--surface-condition] [--jobs J] [--out DIR] [--vesph PATH]
        [--only LABEL ...] [--dry-run] [--measure-only] [--no-png]

    /usr/bin/python3 tools/die_swell_study.py convergence [--across N N N] [--re RE ...] [...]
        the Newtonian die (cases/die_swell_newtonian.toml) under refinement, with the
        Richardson-extrapolated swell and the observed order: its own options, see
        vesph/studies/die_swell_convergence.py (`die_swell_study.py convergence --help`)

STUDY is one of (thesis §4.4; v is the centreline velocity, De = |alpha1| v / (mu W),
Re = rho W v / mu with rho = 1000 kg/m^3, mu = 10 Pa s, W = 0.01 m; alpha2 = -0.1 alpha1):

  deborah      Table 4-1: Re = 5 (v = 5 m/s, alpha1 = 0, -4e-4, -2e-3, -4e-3, -6e-3) and
               Re = 10 (v = 10 m/s, alpha1 = 0, -2e-4, -1e-3, -2e-3, -3e-3, -4e-3, -5e-3);
               swell ratio against De (thesis Fig. 4-14)
  contraction  §4.4.3: alpha1 = -4e-3 and +4e-3 at v = 9.5 m/s (De = 0.38), and the
               Newtonian fluid (alpha1 = 0) at the same v: the reference either sign is
               measured against
  forms        Fig. 4-6: Rivlin-Ericksen and CEF x the four convected derivatives at
               v = 6.8 m/s, alpha1 = -4e-3 (De = 0.272)
  procedures   §4.4.2: Case 1-4 at v = 3.4 m/s, alpha1 = -2.8e-3 (De = 0.0952)
  wsph_isph    §4.4.6: WCSPH and ISPH at v = 6.8 m/s, alpha1 = -4e-3 (thesis 1.362, 1.355);
               the ISPH scene: p = 0 on detected free surface, symmetric grad p (eq. 3.18),
               predictor projection, density relaxation over 0.32 ms (docs/user-guide.md [solver])
  frontier     beyond §4.4.5's limits (De 0.3 at Re 5, 0.5 at Re 10): Re = 10 with
               De = 0.75, 1.0, 1.5, 2.0 (leapfrog) and 1.0, 1.5 (adaptive ARKODE), Re = 5
               with De = 0.4, 1.0 (leapfrog) and 1.0 (ARKODE); and the Oldroyd-B fluid of
               the same viscosity and first normal-stress coefficient at Re = 10, De = 0.5,
               1, 2 (leapfrog) and 1 (ARKODE)

The feed is the prescribed fully developed profile (mean velocity v/1.5): the thesis tuned a
body force F per run to reach v (its F values are listed in the table for reference); the
prescribed feed sets v directly. Every run keeps the base case's momentum form (Rivlin-
Ericksen, contravariant, procedure 3, symmetric grad p, quasi-steady DA/Dt), its stabilisers
(delta-SPH 0.1, XSPH 0.5) and the leapfrog, unless the study varies them. The sound speed is
c = 120 m/s * max(1, v / 6.8 m/s) (Mach <= 0.057); the run lasts 0.045 s * 6.8 / v (the
front passes the last station after about a third of it; the forms and procedures studies
run 0.6 of that), frames every 0.002 s * 6.8 / v.

Resolution: --across N particles across the die (default 10; the thesis: 25), dx = W/N,
h = 1.6 dx, five dummy layers and a five-column inflow buffer (support 4.8 dx); the die runs
from x = 0.15 m to the exit at 0.2 m, the outflow plane at 0.30 m.

Per run (in OUT/STUDY/LABEL/): the scene (LABEL.toml), the vesph output and log, and the
files of tools/die_swell_measure.py. A run counts as stable when vesph finished (exit 0: no
NaN, no particle out of the domain, density within the run's limits), the extrudate is one
piece in the last frame (fluid particles with die exit - W <= x <= 0.28 m, linked at 1.5 dx:
one cluster of >= 5 particles, no more than 5 particles detached), and the average swell
ratio is defined over the later half of the run. Its fluctuation there (the standard
deviation of the average, swell_std) is reported beside it: at 10 particles across one row
is 0.1 of the ratio. removed_at_outflow counts the particles the outflow plane (x = 0.30 m)
removed: 0 means the front never got there and the extrudate was still developing, so its
"steady" swell is a start-up value (strongly swelling extrudates advance slowly: at a swell
ratio s the front moves at about (v/1.5)/s). Per study: OUT/STUDY/STUDY.csv (one row per run:
the parameters, exit status, steps, wall time, steady swell mean/std per station and average,
the filled (void-free) swell of die_swell_measure.py, clusters, detached particles,
die_face_residue, removed_at_outflow, stable), and OUT/STUDY/STUDY.png. die_face_residue
(printed as "face") counts the particles off the largest piece that sit against the die's end
face (outside the die's width, within 3 dx of the exit): the start-up front's stragglers,
which the wall holds there for the rest of the run. They are included in clusters and
detached (and so in the stable flag); the column tells them apart from an extrudate that
breaks up.

--scheme isph runs every run of the named studies with the wsph_isph study's ISPH scene
(projection instead of the equation of state) and files them under OUT/STUDY_isph/ (CSV
STUDY_isph.csv), beside the WCSPH ones; not with wsph_isph, which has both.

--shifting A adds particle shifting to every run ([effects.particle_shifting], coefficient A,
speed U = the feed's mean velocity; docs/theory.md §5.14) with [effects.free_surface]
(number density, threshold 0.8, where the scene has no detection) for its surface band, and
files the runs under OUT/STUDY_shifting (OUT/STUDY_isph_shifting with --scheme isph).

--room R sets the domain's half-height about the die's centreline to R die widths (default
1.5: y from -0.01 to 0.02 m, the base case's). A particle that crosses the domain's edge ends
the run, so a strongly swelling extrudate (swell ratio near 2R) or a front that curls back
over the die's outer faces needs more room: --room 3.5 (y from -0.03 to 0.04 m). Results go
under OUT/STUDY_roomR (after the _isph/_shifting suffixes).

--wall-floor P gives both die walls of every WCSPH run pressure_floor = P (Pa; docs/user-guide.md
[[blocks]]): the walls take no pressure below P from the fluid. At 0 they push but never pull:
the die's end face no longer holds back the extrudate's stretched surface rows within a kernel
support of the lip (docs/studies.md §5, "The die's lip pulls"). ISPH runs solve their wall
pressures and are left as they are (--scheme isph refuses the option; in wsph_isph it applies
to the WCSPH run). Results go under OUT/STUDY_floorP (after the other suffixes).

--surface-condition gives every WCSPH run the free surface's normal stress balance,
[effects.surface_pressure] (p = n.T.n on the flagged particles, thesis §4.2; theory.md §5.12),
with the ISPH scene's flags ([effects.free_surface] threshold 0.97, where p = 0 is imposed in
ISPH): the two conditions ISPH has at the lip and WCSPH lacks. ISPH runs are left alone (not
with --scheme isph). Results go under OUT/STUDY_sp (last suffix).

--isph-surface normal_stress gives every ISPH run the stress-free surface of the converged
Newtonian ISPH die (cases/die_swell_newtonian_isph.toml): [solver] surface_pressure =
"normal_stress" (p = n.T.n on the flagged rows, T the viscous and elastic stress),
[effects.viscosity] form = "stress" where the run has the viscous term, and the renormalised
velocity gradient (docs/theory.md §10). Results go under OUT/STUDY_ns (last suffix).

--dry-run writes the scenes and prints the commands without running them; --measure-only
tabulates runs already present. --only LABEL restricts a study to the named runs.

Exit status: 0 when every run was made (or tabulated); 1 when a run could not be measured
at all (no output); 2 for bad arguments. An unstable run is a result, not an error.
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
import time
import tomllib

from vesph import REPO as ROOT, tool_command, tool_environment

BASE_CASE = os.path.join(ROOT, "cases", "die_swell_second_order_fluid.toml")

RHO, MU, W = 1000.0, 10.0, 0.01           # kg/m^3, Pa s, m (thesis §4.3)
DIE_INLET, DIE_EXIT, OUTFLOW = 0.15, 0.2, 0.30
ROOM = 1.5          # domain half-height about the die's centreline, die widths (the base case's)


def deborah(alpha1, v):
    return abs(alpha1) * v / (MU * W)


def reynolds(v):
    return RHO * W * v / MU


class Run:
    """One run of a study: a label and its parameters."""

    def __init__(self, label, v, alpha1, form="rivlin_ericksen", derivative="contravariant",
                 procedure=3, scheme="wcsph", integrator="leapfrog", thesis_force=None,
                 thesis_swell=None, duration=1.0, model="second_order_fluid"):
        self.label, self.v, self.alpha1 = label, v, alpha1
        self.form, self.derivative, self.procedure = form, derivative, procedure
        self.scheme, self.integrator = scheme, integrator
        self.thesis_force, self.thesis_swell = thesis_force, thesis_swell
        self.duration = duration      # the run lasts duration * 0.045 s * 6.8 / v
        # "second_order_fluid", or "oldroyd_b": the Oldroyd-B fluid with the same viscometric
        # functions in steady shear as the case's form (viscosity mu; first normal-stress
        # coefficient Psi1 = 2 eta_p lambda = -2 alpha1, theory.md §5.7 table, Rivlin-Ericksen
        # contravariant; but N2 = 0, where the second-order fluid has alpha2), solvent ratio
        # eta_s/mu = 1/9.
        self.model = model

    @property
    def De(self):
        return deborah(self.alpha1, self.v)

    @property
    def Re(self):
        return reynolds(self.v)


def study_runs(study):
    if study == "deborah":
        runs = []
        for v, table in ((5.0, [(4100, 0.0), (3870, -4e-4), (2780, -2e-3), (1710, -4e-3),
                                (1245, -6e-3)]),
                         (10.0, [(8170, 0.0), (7410, -2e-4), (5670, -1e-3), (3720, -2e-3),
                                 (2578, -3e-3), (1950, -4e-3), (1549, -5e-3)])):
            for F, a1 in table:
                runs.append(Run(f"re{v:g}_de{deborah(a1, v):g}", v, a1, thesis_force=F))
        return runs
    if study == "contraction":
        # The Newtonian run at the same v: at a finite Reynolds number the Newtonian jet's own
        # swell is not 1, so "contracts" means narrower than it, not only narrower than W.
        return [Run("swell_a1_-4e-3", 9.5, -4e-3, thesis_force=18800),
                Run("contract_a1_+4e-3", 9.5, 4e-3, thesis_force=200000),
                Run("newtonian_a1_0", 9.5, 0.0)]
    if study == "forms":
        # Shorter runs (0.6: to 0.027 s, the front past x = 0.25 m from about 0.014 s): the
        # question is which forms swell, not the last digit of the swell.
        return [Run(f"{form}_{d}", 6.8, -4e-3, form=form, derivative=d, thesis_force=18800,
                    duration=0.6)
                for form in ("rivlin_ericksen", "cef")
                for d in ("contravariant", "covariant", "mixed", "jaumann")]
    if study == "procedures":
        return [Run(f"case{k}", 3.4, -2.8e-3, procedure=k, duration=0.6) for k in (1, 2, 3, 4)]
    if study == "wsph_isph":
        return [Run("wcsph", 6.8, -4e-3, thesis_swell=1.362),
                Run("isph", 6.8, -4e-3, scheme="isph", thesis_swell=1.355)]
    if study == "frontier":
        # The leapfrog at and beyond the thesis' limits; the adaptive ARKODE (several right-hand
        # sides a step: the costlier runs) at De = 1 and beyond. De <= 0.5 (Re 10) and <= 0.3
        # (Re 5) under the leapfrog are the deborah study's.
        runs = []
        for v, integ, des in ((10.0, "leapfrog", (0.75, 1.0, 1.5, 2.0)),
                              (10.0, "arkode", (1.0, 1.5)),
                              (5.0, "leapfrog", (0.4, 1.0)), (5.0, "arkode", (1.0,))):
            for de in des:
                runs.append(Run(f"re{v:g}_de{de:g}_{integ}", v, -de * MU * W / v, integrator=integ))
        # The second-order fluid loses its dissipation where the local Weissenberg number
        # |alpha1| gamma_dot / mu exceeds 1 (docs/theory.md): beyond, the Oldroyd-B fluid of the
        # same mu and Psi1 (well posed at every Weissenberg number).
        for integ, des in (("leapfrog", (0.5, 1.0, 2.0)), ("arkode", (1.0,))):
            for de in des:
                runs.append(Run(f"re10_de{de:g}_oldroyd_b_{integ}", 10.0, -de * MU * W / 10.0,
                                integrator=integ, model="oldroyd_b"))
        return runs
    raise ValueError(study)


STUDIES = ("deborah", "contraction", "forms", "procedures", "wsph_isph", "frontier")


# ------------------------------------------------------------------------------ scenes
def g6(x):
    """x to six significant digits (readable scene files)."""
    return float(f"{x:.6g}")


def scene_for(run, across, shifting=0.0, room=ROOM, wall_floor=None, surface=False, isph_surface="zero"):
    """The scene dict of a run: the base case with the run's parameters and resolution; with
    shifting > 0, particle shifting of that coefficient (speed: the feed's mean velocity); the
    domain reaches room die widths above and below the die's centreline; with wall_floor (Pa)
    a WCSPH run's die walls take no pressure below it; with surface, a WCSPH run imposes the
    free surface's normal stress balance on particles flagged at threshold 0.97; with
    isph_surface = "normal_stress" an ISPH run takes p = n.T.n on its flagged rows, the viscous
    term in the stress form and the renormalised velocity gradient."""
    with open(BASE_CASE, "rb") as fh:
        s = tomllib.load(fh)
    s = copy.deepcopy(s)
    dx = W / across
    depth = 5 * dx                       # >= the quintic support 3 h = 4.8 dx
    s["name"] = run.label
    s["particles"]["spacing"] = dx
    s["domain"]["min"] = [DIE_INLET - depth - 2 * dx, g6(W / 2 - room * W)]
    s["domain"]["max"] = [s["domain"]["max"][0], g6(W / 2 + room * W)]
    fluid, lower, upper = s["blocks"]
    fluid["min"], fluid["max"] = [DIE_INLET, 0.0], [DIE_EXIT, W]
    lower["min"], lower["max"] = [DIE_INLET - depth, -depth], [DIE_EXIT, 0.0]
    upper["min"], upper["max"] = [DIE_INLET - depth, W], [DIE_EXIT, W + depth]
    for wall in (lower, upper):          # the case's wetted faces (session 26): not in the studies
        wall.pop("wetted_face", None)
    if wall_floor is not None and run.scheme == "wcsph":
        lower["pressure_floor"] = upper["pressure_floor"] = float(wall_floor)
    inflow = s["inflow"]
    inflow["min"], inflow["max"] = [DIE_INLET - depth, 0.0], [DIE_INLET, W]
    scale = 6.8 / run.v
    inflow["mean_velocity"] = g6(run.v / 1.5)
    inflow["ramp_time"] = g6(0.005 * scale)
    s["outflow"]["position"] = OUTFLOW
    e = s["effects"]
    # The studies' baseline is the case as they were measured with it (before session 25):
    # Morris' Laplacian with the velocity gradient of Fang eq. (23), every wall particle in the
    # pressure force and seen from everywhere, no shifting. The case now carries the stress form,
    # the die walls' wetted faces and shifting (issue 35, sessions 25-26); they are taken out here
    # (the faces above) so that every documented study command builds the scene it was measured with.
    e["pressure_gradient"] = {"form": "symmetric"}
    e["viscosity"] = {}
    e["velocity_gradient"] = {}
    for key in ("free_surface", "particle_shifting"):
        e.pop(key, None)
    sof = e["second_order_fluid"]
    sof.update(form=run.form, derivative=run.derivative, alpha1=run.alpha1,
               alpha2=g6(-0.1 * run.alpha1), procedure=run.procedure)
    if run.procedure != 3:
        del e["viscosity"]               # Case 1, 2, 4 carry tau = mu A in their own divergence
    if run.procedure == 4:
        del e["stress_divergence"]       # Case 4 computes div T from the velocity derivatives
    e["equation_of_state"]["sound_speed"] = g6(120.0 * max(1.0, run.v / 6.8))
    if run.model == "oldroyd_b":
        # Same mu = eta_s + eta_p and Psi1 = 2 eta_p lambda = -2 alpha1 (alpha1 < 0).
        eta_p = MU * 8.0 / 9.0
        del e["second_order_fluid"]
        s["fluid"]["viscosity"] = g6(MU - eta_p)
        e["oldroyd_b"] = {"relaxation_time": g6(-run.alpha1 / eta_p),
                          "polymer_viscosity": g6(eta_p)}
    if run.scheme == "isph":
        # Projection instead of the equation of state: no density evolution, no sound speed;
        # p = 0 on the free surface needs its detection (docs/user-guide.md, [solver]).
        for k in ("continuity", "equation_of_state", "density_diffusion"):
            e.pop(k, None)
        e["free_surface"] = {"threshold": 0.97}
        # The whole pressure solved each step from the velocity with the carried pressure force
        # taken out ("predictor"), the symmetric grad p (thesis eq. 3.18) in the right-hand side
        # and in the velocity correction, and the particles' number-density error relaxed by
        # the source over 0.32 ms (density_relaxation_time; a tenth per step of the 10-across
        # die's 3.2e-5 s, and about the time the feed takes to move 1 mm): without it the approximate
        # projection lets the die's fluid pack 7-14 % closer than its lattice and flow 10 %
        # slower than the feed; with no-penetration walls instead the die's pressure runs in a
        # three-step cycle (docs/studies.md §5). With the incremental form the symmetric grad p
        # blows the die up at the exit within 3.5 ms.
        s["solver"] = {"scheme": "isph", "linear_solver": "umfpack", "gradient": "symmetric",
                       "carried_pressure": "predictor", "density_relaxation_time": 3.2e-4}
        if isph_surface == "normal_stress":
            # The stress-free surface of the converged Newtonian ISPH die
            # (cases/die_swell_newtonian_isph.toml; docs/theory.md §10): the flagged rows'
            # Dirichlet pressure n.T.n (T: mu (kappa + kappa^T) and the elastic stress), which
            # the symmetric gradient balances against the stress form's surface traction.
            s["solver"]["surface_pressure"] = "normal_stress"
            e["velocity_gradient"] = {"form": "renormalised"}
            if "viscosity" in e:
                e["viscosity"] = {"form": "stress"}
    if shifting > 0:
        # The surface band of the shifting needs the free-surface flags (theory.md §5.14);
        # ISPH scenes have them already.
        e.setdefault("free_surface", {"threshold": 0.8})
        e["particle_shifting"] = {"coefficient": g6(shifting), "speed": g6(run.v / 1.5)}
    if surface and run.scheme == "wcsph":
        # The ISPH scene's flags (its p = 0 rows): the particles at the lip, whose supports
        # the die's wall fills, are flagged at 0.97 and not at 0.8 (docs/studies.md §5).
        e.setdefault("free_surface", {})["threshold"] = 0.97
        e["surface_pressure"] = {}
    s["integrator"] = {"type": run.integrator}
    s["time"] = {"end": g6(0.045 * scale * run.duration)}
    s["output"] = {"interval": g6(0.002 * scale)}
    return s


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(f"no TOML form for {v!r}")


def toml_dumps(table, prefix=""):
    """The subset of TOML the scenes use: scalars, arrays, tables, arrays of tables."""
    out = []
    for k, v in table.items():
        if not isinstance(v, dict) and not (isinstance(v, list) and v and isinstance(v[0], dict)):
            out.append(f"{k} = {toml_value(v)}")
    for k, v in table.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            if any(not isinstance(x, dict) for x in v.values()) or not v:
                out.append(f"\n[{name}]")
            out.append(toml_dumps(v, name + "."))
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for item in v:
                out.append(f"\n[[{name}]]")
                out.append(toml_dumps(item, name + "."))
    return "\n".join(x for x in out if x != "")


# ------------------------------------------------------------------------------ running
def run_scene(scene_path, d, vesph):
    """Run vesph on scene_path with output in d; returns (exit status, wall time s). The log is
    d/run.log."""
    t0 = time.time()
    with open(os.path.join(d, "run.log"), "w") as log:
        rc = subprocess.call([vesph, "run", scene_path, "-o", d, "--quiet"], stdout=log,
                             stderr=subprocess.STDOUT)
    return rc, time.time() - t0


def run_one(run, d, vesph):
    """Run vesph on d/LABEL.toml (run_scene)."""
    return run_scene(os.path.join(d, run.label + ".toml"), d, vesph)


def extrudate_clusters(h5, frame=None):
    """(clusters of >= 5 particles, detached particles, die-face residue) of the extrudate in the
    last frame (or in frame index `frame`). The residue: the particles off the largest piece
    that lie against the die's end face (outside the die's width, less than 3 dx beyond the
    exit), where the start-up front's stragglers stay held by the wall; they are counted among
    clusters/detached as well."""
    import numpy as np
    from vesph.measure.drop import clusters
    from vesph.measure.die_swell import Run

    r = Run(h5)
    try:
        k = len(r.frames) - 1 if frame is None else frame
        fr = r.read_frame(k)
        if fr is None and k > 0 and frame is None:
            fr = r.read_frame(k - 1)
        pos = fr["position"][fr["kind"] == 0]
        pos = pos[(pos[:, 0] >= DIE_EXIT - W) & (pos[:, 0] <= 0.28)]
        n, detached, _, _, largest = clusters(pos, 1.5 * r.dx, 5)
        face = (pos[:, 0] < DIE_EXIT + 3 * r.dx) & ((pos[:, 1] < 0.0) | (pos[:, 1] > W))
        return n, detached, int(np.count_nonzero(face & ~largest))
    finally:
        r.close()


EXIT_OF_STATUS = {"ok": 0, "diverged": 3, "interrupted": 130}


def run_summary(d, rc, wall):
    """(summary.json of the run in d as a dict or None, exit status, wall time s). rc None
    (--measure-only): the exit status and wall time from the summary (1 and nan without one)."""
    summ = os.path.join(d, "summary.json")
    js = None
    if os.path.exists(summ):
        with open(summ) as fh:
            js = json.load(fh)
    if rc is None:
        rc = EXIT_OF_STATUS.get((js or {}).get("status"), 1)
        wall = (js or {}).get("wall_seconds")
        wall = math.nan if wall is None else wall
    return js, rc, wall


def measure(run, d, rc, wall, png):
    """The study's row for one run. rc None (--measure-only): the exit status and wall time
    from the run's summary.json; then None when the run left no summary."""
    h5 = os.path.join(d, run.label + ".h5")
    measure_only = rc is None
    js, rc, wall = run_summary(d, rc, wall)
    if measure_only and js is None:
        return None
    row = {"label": run.label, "v_m_s": run.v, "Re": run.Re, "De": round(run.De, 6),
           "alpha1_Pa_s2": run.alpha1, "alpha2_Pa_s2": -0.1 * run.alpha1, "form": run.form,
           "derivative": run.derivative, "procedure": run.procedure, "scheme": run.scheme,
           "integrator": run.integrator, "model": run.model,
           "thesis_force_N_kg": run.thesis_force,
           "thesis_swell": run.thesis_swell, "exit_status": rc, "status": "",
           "end_time_s": math.nan, "steps": math.nan, "wall_s": round(wall, 1),
           "stable": False}
    if js is not None:
        row["status"] = js.get("status", "")
        row["end_time_s"] = js.get("final_time", math.nan)
        row["steps"] = js.get("steps", math.nan)
        row["max_density_deviation"] = js.get("max_density_deviation", math.nan)
        # 0: the front never reached the outflow plane, the extrudate was still developing
        flow = js.get("flow") or {}
        row["removed_at_outflow"] = flow.get("removed", math.nan)
        if js.get("status") != "ok" and "message" in js:
            row["message"] = js["message"]
    if not os.path.exists(h5):
        return row
    m = subprocess.run(tool_command("vesph.measure.die_swell") + [h5,
                        "--out-dir", d, "--prefix", run.label] + ([] if png else ["--no-png"]),
                       capture_output=True, text=True, env=tool_environment())
    sj = os.path.join(d, run.label + "_summary.json")
    if m.returncode == 0 and os.path.exists(sj):
        with open(sj) as fh:
            ms = json.load(fh)
        num = lambda v: math.nan if v is None else float(v)  # noqa: E731 (JSON null: NaN)
        avg = ms["average"]
        row["swell_mean"] = num(avg["mean"])
        row["swell_std"] = num(avg["std"])
        for s in ms["stations"]:
            row[f"swell_x{s['x_m']:g}"] = num(s["mean"])
        if ms.get("filled"):
            row["filled_mean"] = num(ms["filled"]["mean"])
            row["filled_std"] = num(ms["filled"]["std"])
        row["frames_used"] = ms["frames_used"]
    else:
        row["measure_error"] = (m.stderr or m.stdout).strip().splitlines()[-1:]
    try:
        row["clusters"], row["detached"], row["die_face_residue"] = extrudate_clusters(h5)
    except Exception as ex:  # an unreadable output is reported, not fatal for the study
        row["clusters"], row["detached"], row["die_face_residue"] = math.nan, math.nan, math.nan
        row["measure_error"] = str(ex)
    mean = row.get("swell_mean")
    row["stable"] = bool(rc == 0 and row["clusters"] == 1 and row["detached"] <= 5
                         and mean is not None and math.isfinite(mean))
    return row


COLUMNS = ["label", "model", "v_m_s", "Re", "De", "alpha1_Pa_s2", "alpha2_Pa_s2", "form", "derivative",
           "procedure", "scheme", "integrator", "thesis_force_N_kg", "thesis_swell",
           "exit_status", "status", "end_time_s", "steps", "wall_s", "max_density_deviation", "swell_mean", "swell_std",
           "swell_x0.21", "swell_x0.23", "swell_x0.25", "filled_mean", "filled_std", "frames_used", "clusters", "detached",
           "die_face_residue", "removed_at_outflow", "stable", "message", "measure_error"]


def fmt(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return "nan" if not math.isfinite(v) else f"{v:.6g}"
    return str(v)


def write_rows(path, columns, rows):
    """A study's CSV: the header, then each row's cells in the columns' order (fmt)."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(columns)
        for row in rows:
            w.writerow([fmt(row.get(c)) for c in columns])


def short(v):
    return f"{v:.4g}" if isinstance(v, float) else fmt(v)


def plot(study, rows, png, title=None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    if study in ("deborah", "frontier"):
        nan = math.nan
        val = lambda r, k: r.get(k) if isinstance(r.get(k), float) else nan  # noqa: E731
        for v, integ, model, mk in ((5.0, "leapfrog", "second_order_fluid", "o-"),
                                    (10.0, "leapfrog", "second_order_fluid", "s-"),
                                    (5.0, "arkode", "second_order_fluid", "o--"),
                                    (10.0, "arkode", "second_order_fluid", "s--"),
                                    (10.0, "leapfrog", "oldroyd_b", "^-"),
                                    (10.0, "arkode", "oldroyd_b", "^--")):
            sel = sorted((r for r in rows if r["v_m_s"] == v and r["integrator"] == integ
                          and r["model"] == model), key=lambda r: r["De"])
            if not sel:
                continue
            name = f"Re = {v:g}, {integ}" + (", Oldroyd-B" if model == "oldroyd_b" else "")
            de = [r["De"] for r in sel]
            line, = ax.plot(de, [val(r, "swell_mean") for r in sel], mk, label=name + ": envelope")
            ax.plot(de, [val(r, "filled_mean") for r in sel], mk[0] + ":", color=line.get_color(),
                    mfc="none", label=name + ": filled")
            bad = [r for r in sel if not r["stable"]]
            if bad:   # unstable runs at ratio 1 when they have no steady value
                y = [val(r, "swell_mean") for r in bad]
                ax.plot([r["De"] for r in bad], [q if math.isfinite(q) else 1.0 for q in y],
                        "rx", ms=10)
        ax.set_xlabel("De = |alpha1| v / (mu W)")
        ax.set_ylabel("steady swell ratio (mean of x = 0.21, 0.23, 0.25 m)")
        ax.legend(title="red x: not stable")
    else:
        labels = [r["label"] for r in rows]
        vals = [r["swell_mean"] if isinstance(r.get("swell_mean"), float) else math.nan for r in rows]
        errs = [r["swell_std"] if isinstance(r.get("swell_std"), float) else 0.0 for r in rows]
        colors = ["tab:blue" if r["stable"] else "tab:red" for r in rows]
        ax.bar(range(len(rows)), [v if math.isfinite(v) else 0.0 for v in vals],
               yerr=[e if math.isfinite(e) else 0.0 for e in errs], color=colors)
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_xticks(range(len(rows)))
        ax.set_xticklabels(labels, rotation=30, ha="right")
        ax.set_ylabel("steady swell ratio (red: not stable)")
    ax.set_title(f"die swell study: {title or study}")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def main(argv=None):
    args = sys.argv[1:] if argv is None else list(argv)
    if args[:1] == ["convergence"]:
        # The Newtonian die under refinement has its own options (several resolutions and
        # Reynolds numbers, one variant of the case): vesph/studies/die_swell_convergence.py.
        from vesph.studies import die_swell_convergence
        return die_swell_convergence.main(args[1:])
    ap = argparse.ArgumentParser(prog="die_swell_study.py", description=__doc__.split("\n")[0])
    ap.add_argument("studies", nargs="+", choices=STUDIES, metavar="STUDY",
                    help="one or more of " + ", ".join(STUDIES))
    ap.add_argument("--across", type=int, default=10, metavar="N",
                    help="particles across the die (default 10; thesis 25)")
    ap.add_argument("--scheme", choices=("wcsph", "isph"), default="wcsph",
                    help="pressure treatment of every run (default wcsph; isph: the wsph_isph "
                         "study's ISPH scene, results under OUT/STUDY_isph)")
    ap.add_argument("--shifting", type=float, default=0.0, metavar="A",
                    help="particle shifting of coefficient A in every run (default 0: none; "
                         "results under OUT/STUDY_shifting)")
    ap.add_argument("--room", type=float, default=ROOM, metavar="R",
                    help=f"domain half-height about the die's centreline in die widths (default "
                         f"{ROOM:g}: y from -0.01 to 0.02 m; results under OUT/STUDY_roomR "
                         f"otherwise)")
    ap.add_argument("--wall-floor", type=float, default=None, metavar="P",
                    help="pressure_floor P (Pa) on the die walls of every WCSPH run (0: walls that "
                         "push but never pull; results under OUT/STUDY_floorP)")
    ap.add_argument("--surface-condition", action="store_true",
                    help="every WCSPH run imposes the free surface's normal stress balance "
                         "([effects.surface_pressure], flags at 0.97; results under OUT/STUDY_sp)")
    ap.add_argument("--isph-surface", choices=("zero", "normal_stress"), default="zero",
                    help="the ISPH runs' surface: zero (p = 0, default) or normal_stress (p = n.T.n "
                         "with the stress form of the viscous term and the renormalised velocity "
                         "gradient, the converged Newtonian setting; results under OUT/STUDY_ns)")
    ap.add_argument("--jobs", type=int, default=max(1, os.cpu_count() or 1), metavar="J",
                    help="runs at once (each uses one core: set OMP_NUM_THREADS)")
    ap.add_argument("--out", default="out/die_swell_study", metavar="DIR")
    ap.add_argument("--vesph", default=os.path.join(ROOT, "build", "vesph"), metavar="PATH")
    ap.add_argument("--only", nargs="+", metavar="LABEL")
    ap.add_argument("--dry-run", action="store_true")
    ap.add_argument("--measure-only", action="store_true")
    ap.add_argument("--no-png", action="store_true")
    a = ap.parse_args(args)
    if a.across < 5:
        ap.error("--across must be >= 5 (particles across the die)")
    if a.shifting < 0:
        ap.error("--shifting must be >= 0")
    if a.room < 1.5:
        ap.error("--room must be >= 1.5 (die widths: the die's walls and their dummy layers "
                 "must lie inside the domain)")
    if not (a.dry_run or a.measure_only) and not shutil.which(a.vesph) and not os.path.exists(a.vesph):
        ap.error(f"--vesph {a.vesph}: no such executable (build first: see README)")
    if a.wall_floor is not None and not math.isfinite(a.wall_floor):
        ap.error("--wall-floor must be a finite pressure (Pa)")
    if a.surface_condition and a.scheme == "isph":
        ap.error("--surface-condition: ISPH runs impose p = 0 on their flagged particles already")
    if a.wall_floor is not None and a.scheme == "isph":
        ap.error("--wall-floor: ISPH runs solve their wall pressures (pressure_floor is WCSPH only)")
    if a.isph_surface == "normal_stress" and a.scheme != "isph" and a.studies != ["wsph_isph"]:
        ap.error("--isph-surface applies to ISPH runs: add --scheme isph (or run wsph_isph)")
    if a.scheme == "isph" and "wsph_isph" in a.studies:
        ap.error("--scheme isph: the wsph_isph study already runs both schemes")
    status = 0
    for study in a.studies:
        runs = study_runs(study)
        if a.scheme == "isph":
            for r in runs:
                r.scheme = "isph"
        if a.only:
            unknown = set(a.only) - {r.label for r in runs}
            runs = [r for r in runs if r.label in a.only]
            if not runs:
                ap.error(f"--only: no run of study {study} is named {sorted(unknown)}; "
                         f"its runs: {[r.label for r in study_runs(study)]}")
        name = study + ("_isph" if a.scheme == "isph" else "") + ("_shifting" if a.shifting > 0 else "") \
            + (f"_room{a.room:g}" if a.room != ROOM else "") \
            + (f"_floor{a.wall_floor:g}" if a.wall_floor is not None else "") \
            + ("_sp" if a.surface_condition else "") \
            + ("_ns" if a.isph_surface == "normal_stress" else "")
        sd = os.path.join(a.out, name)
        todo = []
        for r in runs:
            d = os.path.join(sd, r.label)
            os.makedirs(d, exist_ok=True)
            if not a.measure_only:
                with open(os.path.join(d, r.label + ".toml"), "w") as fh:
                    fh.write(f"# die_swell_study.py {name}: {r.label} (De = {r.De:.4g}, "
                             f"Re = {r.Re:.4g}, {a.across} across)\n")
                    fh.write(toml_dumps(scene_for(r, a.across, a.shifting, a.room, a.wall_floor,
                                                  a.surface_condition, a.isph_surface)) + "\n")
            todo.append((r, d))
        if a.dry_run:
            for r, d in todo:
                print(f"{a.vesph} run {os.path.join(d, r.label + '.toml')} -o {d} --quiet")
            continue
        results = {}
        if not a.measure_only:
            env_note = os.environ.get("OMP_NUM_THREADS")
            print(f"== {name}: {len(todo)} runs, {a.jobs} at once, {a.across} across"
                  + (f", OMP_NUM_THREADS={env_note}" if env_note else ""), flush=True)
            with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
                futs = {pool.submit(run_one, r, d, a.vesph): (r, d) for r, d in todo}
                for f in concurrent.futures.as_completed(futs):
                    r, d = futs[f]
                    results[r.label] = f.result()
                    print(f"   {r.label}: exit {results[r.label][0]}, "
                          f"{results[r.label][1]:.0f} s", flush=True)
        rows = []
        for r, d in todo:
            rc, wall = results.get(r.label, (None, math.nan))   # None: --measure-only
            row = measure(r, d, rc, wall, png=not a.no_png)
            if row is None:
                print(f"   {r.label}: no output in {d}")
                status = 1
                continue
            rows.append(row)
        csv_path = os.path.join(sd, name + ".csv")
        write_rows(csv_path, COLUMNS, rows)
        print(f"== {name} ({a.across} across)")
        print(f"   {'label':<28}{'De':>7}{'Re':>6}{'exit':>6}{'swell':>9}{'std':>8}"
              f"{'filled':>9}{'clust':>6}{'det':>5}{'face':>5}{'out':>7}  stable")
        for row in rows:
            print(f"   {row['label']:<28}{row['De']:7.3g}{row['Re']:6.3g}{row['exit_status']:6d}"
                  f"{short(row.get('swell_mean')):>9}{short(row.get('swell_std')):>8}"
                  f"{short(row.get('filled_mean')):>9}"
                  f"{fmt(row.get('clusters')):>6}{fmt(row.get('detached')):>5}{fmt(row.get('die_face_residue')):>5}"
                  f"{fmt(row.get('removed_at_outflow')):>7}  "
                  f"{'yes' if row['stable'] else 'NO'}"
                  + (f"   ({row['message']})" if row.get("message") else ""))
        print(f"wrote {csv_path}")
        if rows and not a.no_png:
            png = os.path.join(sd, name + ".png")
            plot(study, rows, png, title=name)
            print(f"wrote {png}")
    return status


if __name__ == "__main__":
    sys.exit(main())
