#!/usr/bin/python3
"""Self-test for tools/poiseuille_check.py, tools/check_output.py,
tools/startup_channel_profiles.py and (when ParaView is installed)
tools/paraview_check.py.

Usage
-----
    /usr/bin/python3 tools/test_tools.py            run all tests
    /usr/bin/python3 tools/test_tools.py --keep DIR  also keep the synthetic
                                                     outputs in DIR
    /usr/bin/python3 tools/test_tools.py --write DIR only write the synthetic
                                                     cases to DIR (no tests)

The tests build small synthetic vesph-1 outputs with h5py in a temporary
directory (nothing is committed): a 2D plane-Poiseuille channel (the
poiseuille_newtonian scene, SI units: m, s, kg, Pa) whose fluid velocities
are the exact analytic profile at t = 0, 0.0225, 0.045, 0.1125, 0.5 s, and a
small 3D box with extra_stress [N,6] and free_surface.  Each is written as
DIR/<name>.h5 + DIR/<name>.xdmf (XDMF 3 in the layout the C++ writer uses)
+ DIR/summary.json.  They then check that
  * analytic_velocity is right (t = 0, walls, steady limit, short-time
    limit, the PDE dv/dt = nu d2v/dy2 + F),
  * poiseuille_check.py reports ~0 error on the exact profile, honours
    --times, writes the CSV and PNG, and fails (exit 1, naming the frame)
    on a perturbed velocity, on a mass drift and on a missing time,
  * check_output.py accepts the good outputs and catches each of a series
    of deliberately broken HDF5 / XDMF files, naming the problem,
  * startup_channel_profiles.py, on synthetic periodic channels (2D with
    40 and 39 rows, 3D, Newtonian without extra_stress, rows jittered in y
    by 0.1 dx or, to force the lattice-bin fallback, 0.45 dx) with known
    fields v_x(x, y, t), T_xx, T_xy, T_yy: the profiles at stations (also
    across the periodic boundary, and with wider bins) and the centreline
    history equal the per-row means computed directly from the lattice
    indices; row clustering; the nearest-frame rule; the error messages
    and exit codes (missing file, not HDF5, not vesph, no fluid, station or
    time out of range, bad options),
  * xpp_steady_shear.py: the steady homogeneous-shear XPP solver (small-rate
    limit = Oldroyd-B, Newton and ODE routes agree, flow-curve inversion,
    channel velocity against quadrature, the 1-D start-up tends to the steady
    channel) and its check on a synthetic XPP channel built from the 1-D
    start-up: passes, and fails on a 5 % error in tau_zz, on a frame-to-frame
    oscillation of the start-up, before the steady state, without an XPP,
  * drop_measure.py, on synthetic drop-impact outputs (lattice disks of
    known width, height and area, a blob flattened on the wall, a disk split
    in two, a disk with a hole, a disk with an open slot, detached particles,
    changed densities, a 3D sphere, two runs compared): the measured columns,
    the cluster / void / crack / nearest-neighbour indicators, the checks' exit codes (--max-volume-error,
    --no-fracture, --expect-fracture, --until) and the error messages,
  * die_swell_measure.py, on synthetic planar die-swell outputs (a 25-row
    die, walls, an inflow buffer and a floor beyond the exit, an extrudate
    growing in length with time and swelling to 29-31 rows, N varying
    between frames; a viscoelastic file with T_xx = a y, T_yy = b,
    T_xy = c (y - W/2) and a Newtonian one): the swell ratios at the
    stations (NaN before the extrudate arrives), the steady mean / std /
    half range, the profiles against the analytic fields, the PNGs,
    --expect-min/--expect-max and the bad-input errors and exit codes,
  * die_swell_study.py: the scenes of every study (they read back from the
    TOML written, the thesis resolution gives the base case's geometry, the
    procedures' effect lists, the ISPH set-up, Table 4-1's Deborah numbers),
    the tabulation of two synthetic runs (one finished and steady, one
    diverged) and the bad-argument errors,
  * paraview_check.py (skipped when ParaView's Python modules are absent)
    reads the synthetic XDMF with the Xdmf3 reader.
Prints one line per test and "N passed, M failed" at the end; exit status
is 0 only when every test passed.
"""

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import traceback

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.dont_write_bytecode = True      # no tools/__pycache__ left behind
PY = "/usr/bin/python3"

import h5py  # noqa: E402

from poiseuille_check import analytic_velocity  # noqa: E402
from startup_channel_profiles import cluster_rows  # noqa: E402

SCENE_2D = """\
name = "poiseuille_newtonian"
dimension = 2
[domain]
min = [0.0, -1.25e-4]
max = [5.0e-4, 1.125e-3]
periodic = [true, false]
[particles]
spacing = 2.5e-5
kernel = "quintic"
smoothing_ratio = 1.6
[fluid]
density = 1000.0     # kg/m^3
viscosity = 1.0e-3   # dynamic, Pa s
[[blocks]]
kind = "fluid"
min = [0.0, 0.0]
max = [5.0e-4, 1.0e-3]
[[blocks]]
kind = "wall"
min = [0.0, -1.25e-4]
max = [5.0e-4, 0.0]
[[blocks]]
kind = "wall"
min = [0.0, 1.0e-3]
max = [5.0e-4, 1.125e-3]
[effects.body_force]
acceleration = [2.0e-4, 0.0]   # m/s^2
[effects.equation_of_state]
sound_speed = { phi = 4.0, delta = 0.01, velocity = 2.5e-5, length = 1.0e-3 }
[output]
times = [0.0225, 0.045, 0.1125, 0.5]
"""

SCENE_3D = """\
name = "box3d"
dimension = 3
[domain]
min = [0.0, 0.0, 0.0]
max = [1.0e-3, 1.0e-3, 1.0e-3]
[particles]
spacing = 2.5e-4
kernel = "wendland_c2"
smoothing_ratio = 1.3
[fluid]
density = 1000.0
viscosity = 1.0e-3
[[blocks]]
kind = "fluid"
min = [0.0, 0.0, 0.0]
max = [1.0e-3, 1.0e-3, 1.0e-3]
[output]
times = [0.1]
"""

F, RHO, MU, H, DX = 2.0e-4, 1000.0, 1.0e-3, 1.0e-3, 2.5e-5
NU = MU / RHO
U_CENTRE = F * H * H / (8 * NU)
TIMES = [0.0, 0.0225, 0.045, 0.1125, 0.5]

# XDMF (NumberType, Precision) for each dataset dtype
XDMF_NT = {"float64": ("Float", 8), "uint8": ("UChar", 1), "uint64": ("UInt", 8)}


# ------------------------------------------------------------ synthetic data
def channel_particles():
    """2D channel: 20 x 50 particles on a dx lattice; 5 wall rows each side."""
    nx, ny_wall, ny_fluid = 20, 5, 40
    xs = (np.arange(nx) + 0.5) * DX
    ys = (np.arange(-ny_wall, ny_fluid + ny_wall) + 0.5) * DX
    X, Y = np.meshgrid(xs, ys, indexing="xy")
    pos = np.column_stack([X.ravel(), Y.ravel()])
    kind = np.where((pos[:, 1] > 0) & (pos[:, 1] < H), 0, 1).astype(np.uint8)
    return pos, kind


def write_h5(path, scene, dim, frames, extra_root=None, fixed_strings=False):
    """frames: list of dicts with keys time, step and dataset arrays.
    fixed_strings: store the string attributes as fixed-length (as plain
    HDF5 C code often does) instead of variable-length UTF-8."""
    S = (lambda v: np.bytes_(v.encode())) if fixed_strings else (lambda v: v)
    with h5py.File(path, "w") as f:
        f.attrs["format"] = S("vesph-1")
        f.attrs["dim"] = np.int64(dim)
        f.attrs["scene"] = S(scene)
        f.attrs["dx"] = np.float64(DX)
        f.attrs["h"] = np.float64(1.6 * DX)
        f.attrs["kernel"] = S("quintic")
        for k, v in (extra_root or {}).items():
            f.attrs[k] = v
        for i, fr in enumerate(frames):
            g = f.create_group(f"frames/{i:06d}")
            g.attrs["time"] = np.float64(fr["time"])
            g.attrs["step"] = np.int64(fr["step"])
            for name, arr in fr.items():
                if name not in ("time", "step"):
                    g.create_dataset(name, data=arr)
        nd = 12
        d = f.create_group("diagnostics")
        for col in ("time", "dt", "kinetic_energy", "mass", "max_speed",
                    "max_density_deviation"):
            d.create_dataset(col, data=np.linspace(0.0, 1.0, nd))


def xdmf_text(h5name, h5path, uint64_type=("UInt", 8), vector_type="Vector",
              time_fmt=repr):
    """XDMF 3 text in the layout of the C++ writer, generated from the file."""
    out = ['<?xml version="1.0" ?>', '<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>',
           '<Xdmf Version="3.0">', ' <Domain>',
           '  <Grid Name="particles" GridType="Collection" CollectionType="Temporal">']
    with h5py.File(h5path, "r") as f:
        dim = int(f.attrs["dim"])
        for name in sorted(f["frames"]):
            g = f["frames"][name]
            N = g["id"].shape[0]
            t = float(g.attrs["time"])

            def item(ds):
                d = g[ds]
                nt, prec = XDMF_NT[d.dtype.name]
                if d.dtype == np.uint64:
                    nt, prec = uint64_type
                dims = " ".join(str(s) for s in d.shape)
                return (f'<DataItem Dimensions="{dims}" NumberType="{nt}" Precision="{prec}" '
                        f'Format="HDF">{h5name}:/frames/{name}/{ds}</DataItem>')

            out.append(f'   <Grid Name="frame_{name}" GridType="Uniform">')
            out.append(f'    <Time Value="{time_fmt(t)}"/>')
            out.append(f'    <Topology TopologyType="Polyvertex" NumberOfElements="{N}" '
                       'NodesPerElement="1"/>')
            out.append(f'    <Geometry GeometryType="{"XY" if dim == 2 else "XYZ"}">')
            out.append(f'     {item("position")}')
            out.append('    </Geometry>')
            types = {"velocity": vector_type, "density": "Scalar", "mass": "Scalar",
                     "pressure": "Scalar", "id": "Scalar", "kind": "Scalar",
                     "free_surface": "Scalar",
                     "extra_stress": "Matrix" if dim == 2 else "Tensor6"}
            for ds in ("velocity", "density", "mass", "pressure", "id", "kind",
                       "extra_stress", "free_surface"):
                if ds in g:
                    out.append(f'    <Attribute Name="{ds}" AttributeType="{types[ds]}" '
                               'Center="Node">')
                    out.append(f'     {item(ds)}')
                    out.append('    </Attribute>')
            out.append('   </Grid>')
    out += ['  </Grid>', ' </Domain>', '</Xdmf>', '']
    return "\n".join(out)


def write_channel_case(d, name="poiseuille_newtonian", times=TIMES, perturb=None,
                       mass_change=None, fixed_strings=False, **xdmf_kw):
    """Write the 2D channel with the exact analytic profile.

    perturb     = (frame index, dv [m/s]) added to the vx of one fluid particle
    mass_change = (frame index, relative change) of one fluid particle's mass
    """
    os.makedirs(d, exist_ok=True)
    pos, kind = channel_particles()
    N = len(kind)
    fl = kind == 0
    rng = np.random.default_rng(1)
    frames = []
    for i, t in enumerate(times):
        vel = np.zeros((N, 2))
        vel[fl, 0] = analytic_velocity(pos[fl, 1], t, F, NU, H, 0.0)
        mass = np.full(N, RHO * DX * DX)
        if perturb and perturb[0] == i:
            j = int(np.flatnonzero(fl)[len(np.flatnonzero(fl)) // 2])
            vel[j, 0] += perturb[1]
        if mass_change and mass_change[0] == i:
            j = int(np.flatnonzero(fl)[0])
            mass[j] *= 1.0 + mass_change[1]
        frames.append({
            "time": t, "step": int(round(t / 1e-4)),
            "id": np.arange(N, dtype=np.uint64),
            "kind": kind,
            "position": pos.copy(),
            "velocity": vel,
            "density": RHO * (1.0 + 1e-4 * rng.standard_normal(N)),
            "mass": mass,
            "pressure": rng.standard_normal(N),
        })
    h5 = os.path.join(d, name + ".h5")
    write_h5(h5, SCENE_2D, 2, frames, fixed_strings=fixed_strings)
    with open(os.path.join(d, name + ".xdmf"), "w") as fh:
        fh.write(xdmf_text(name + ".h5", h5, **xdmf_kw))
    with open(os.path.join(d, "summary.json"), "w") as fh:
        json.dump({"name": name, "frames": len(times)}, fh)
    return h5


def write_3d_case(d, name="box3d", **xdmf_kw):
    os.makedirs(d, exist_ok=True)
    n = 4
    g1 = (np.arange(n) + 0.5) * 2.5e-4
    X, Y, Z = np.meshgrid(g1, g1, g1, indexing="ij")
    pos = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    N = len(pos)
    frames = []
    for i, t in enumerate([0.0, 0.05, 0.1]):
        frames.append({
            "time": t, "step": i * 10,
            "id": np.arange(N, dtype=np.uint64) + np.uint64(2 ** 33),
            "kind": np.zeros(N, np.uint8),
            "position": pos.copy(),
            "velocity": np.tile([1e-3 * t, 0.0, -2e-3 * t], (N, 1)),
            "density": np.full(N, 1000.0),
            "mass": np.full(N, 1000.0 * 2.5e-4 ** 3),
            "pressure": np.zeros(N),
            "extra_stress": np.tile(np.arange(6.0) + t, (N, 1)),
            "free_surface": (pos[:, 2] > 7e-4).astype(np.uint8),
        })
    h5 = os.path.join(d, name + ".h5")
    write_h5(h5, SCENE_3D, 3, frames)
    with open(os.path.join(d, name + ".xdmf"), "w") as fh:
        fh.write(xdmf_text(name + ".h5", h5, **xdmf_kw))
    with open(os.path.join(d, "summary.json"), "w") as fh:
        json.dump({"name": name}, fh)
    return h5


# ---------------------------------------- synthetic start-up channel (profiles)
SCENE_STARTUP = """\
name = "startup_synth"
dimension = {dim}
[domain]
min = [0.0, {ylo!r}{zmin}]
max = [{L!r}, {yhi!r}{zmax}]
periodic = [true, false{zper}]
[particles]
spacing = {dx!r}
[fluid]
density = 1000.0
viscosity = 5.0e-4
[[blocks]]
kind = "fluid"
min = [0.0, 0.0{zmin}]
max = [{L!r}, {H!r}{zmax}]
[[blocks]]
kind = "wall"
min = [0.0, {ylo!r}{zmin}]
max = [{L!r}, 0.0{zmax}]
[[blocks]]
kind = "wall"
min = [0.0, {H!r}{zmin}]
max = [{L!r}, {yhi!r}{zmax}]
[effects.body_force]
acceleration = [2.0e-4, 0.0{zzero}]
{model}
[time]
end = 0.4
"""
SU_NX, SU_TIMES = 20, [0.0, 0.1, 0.2, 0.3, 0.4]
SU_UC, SU_EPS, SU_A, SU_B, SU_C, SU_D = 2.5e-5, 3e-7, 7e-7, 2e-8, 9e-5, -1e-9


def su_fields(x, y, t, yc, a, L):
    """The synthetic fields of the start-up channel: (vx, Txx, Txy, Tyy) [m/s, Pa]."""
    s = t / SU_TIMES[-1]
    Y = (y - yc) / a
    vx = SU_UC * (1 - Y * Y) * s + SU_EPS * np.sin(2 * np.pi * x / L)
    txx = SU_A * Y * Y * s + SU_B * x / L
    txy = -SU_C * Y * s
    tyy = SU_D * s + SU_B * (x / L) ** 2
    return vx, txx, txy, tyy


def write_startup_case(d, ny=40, jitter=0.1, stress=True, dim=2, no_fluid=False):
    """A periodic channel, SU_NX x ny fluid particles on the dx lattice (x exact, y moved
    by up to +-jitter*dx, uniform random), 5 wall rows each side, with the fields of
    su_fields on the fluid and 1e3 (to be ignored) on the walls. 3D: two layers in z.
    Returns (h5 path, info) with info['frames'] = list of (t, x, y, vx, txx, txy, tyy,
    row, col) over the fluid particles (row, col: lattice indices)."""
    os.makedirs(d, exist_ok=True)
    H_ = ny * DX
    L = SU_NX * DX
    yc, a = H_ / 2, H_ / 2
    nz = 2 if dim == 3 else 1
    ii, jj, kk = np.meshgrid(np.arange(SU_NX), np.arange(-5, ny + 5), np.arange(nz),
                             indexing="ij")
    ii, jj, kk = ii.ravel(), jj.ravel(), kk.ravel()
    fl = (jj >= 0) & (jj < ny)
    order = np.argsort(~fl, kind="stable")          # fluid first
    ii, jj, kk, fl = ii[order], jj[order], kk[order], fl[order]
    N = len(ii)
    rng = np.random.default_rng(7)
    z3 = {"zmin": ", 0.0" if dim == 3 else "", "zmax": f", {nz * DX!r}" if dim == 3 else "",
          "zper": ", true" if dim == 3 else "", "zzero": ", 0.0" if dim == 3 else ""}
    model = ("[effects.velocity_gradient]\n[effects.oldroyd_b]\nrelaxation_time = 0.1\n"
             "polymer_viscosity = 5.0e-4\n[effects.stress_divergence]" if stress
             else "[effects.viscosity]")
    scene = SCENE_STARTUP.format(dim=dim, ylo=-5 * DX, yhi=H_ + 5 * DX, L=L, dx=DX, H=H_,
                                 model=model, **z3)
    frames, info = [], []
    for i, t in enumerate(SU_TIMES):
        pos = np.zeros((N, dim))
        pos[:, 0] = (ii + 0.5) * DX
        pos[:, 1] = (jj + 0.5) * DX + np.where(fl, jitter * DX * rng.uniform(-1, 1, N), 0.0)
        if dim == 3:
            pos[:, 2] = (kk + 0.5) * DX
        vx, txx, txy, tyy = su_fields(pos[:, 0], pos[:, 1], t, yc, a, L)
        vel = np.zeros((N, dim))
        vel[:, 0] = np.where(fl, vx, 0.0)
        vel[fl, 1] = 1e-9 * rng.standard_normal(int(fl.sum()))
        kind = np.where(fl, 0, np.where((jj == -1) | (jj == ny), 1, 2)).astype(np.uint8)
        if no_fluid:
            kind[:] = 1
        fr = {"time": t, "step": 10 * i, "id": np.arange(N, dtype=np.uint64), "kind": kind,
              "position": pos, "velocity": vel, "density": np.full(N, 1000.0),
              "mass": np.full(N, 1000.0 * DX ** dim), "pressure": np.zeros(N)}
        if stress:
            T = np.full((N, 3 if dim == 2 else 6), 1e3)
            ixx, ixy, iyy = (0, 1, 2) if dim == 2 else (0, 1, 3)
            T[fl, :] = 5e3                              # xz, yz, zz in 3D: not used
            T[fl, ixx], T[fl, ixy], T[fl, iyy] = txx[fl], txy[fl], tyy[fl]
            fr["extra_stress"] = T
        frames.append(fr)
        info.append((t, pos[fl, 0], pos[fl, 1], vx[fl], txx[fl], txy[fl], tyy[fl],
                     jj[fl], ii[fl]))
    h5 = os.path.join(d, "startup_synth.h5")
    write_h5(h5, scene, dim, frames)
    return h5, {"frames": info, "yc": yc, "a": a, "L": L, "ny": ny}


def read_csv_rows(path):
    import csv as _csv
    with open(path, newline="") as fh:
        return list(_csv.DictReader(fh))


def su_expected_profile(info, frame, cols):
    """Per-row means over the particles of the given lattice columns (exact reference)."""
    t, x, y, vx, txx, txy, tyy, row, col = info["frames"][frame]
    out = []
    for j in range(info["ny"]):
        m = (row == j) & np.isin(col, cols)
        out.append({"y": y[m].mean(), "vx": vx[m].mean(), "txx": txx[m].mean(),
                    "txy": txy[m].mean(), "tyy": tyy[m].mean(),
                    "n1": (txx[m] - tyy[m]).mean(), "count": int(m.sum())})
    return out


# ------------------------------------------------------------------- runner
class Runner:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def run(self, name, fn):
        try:
            fn()
        except AssertionError as e:
            self.failed += 1
            print(f"FAIL  {name}: {e}")
            return
        except Exception:
            self.failed += 1
            print(f"ERROR {name}:")
            traceback.print_exc()
            return
        self.passed += 1
        print(f"ok    {name}")


def tool(script, *args):
    p = subprocess.run([PY, os.path.join(HERE, script), *map(str, args)],
                       capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def expect(cond, msg, out=""):
    if not cond:
        raise AssertionError(msg + ("\n----- output -----\n" + out if out else ""))


def expect_unreadable_files_fail(script, d, not_vesph_attrs, prefix=""):
    """The errors every file-reading tool gives, exit 1: a missing file, a text file, and an
    HDF5 file with the given root attributes that is not a vesph output. With prefix, the
    missing file's message must also carry it (e.g. 'die_swell_measure: error:')."""
    rc, out, err = tool(script, os.path.join(d, "missing.h5"))
    expect(rc == 1 and prefix in err and "no such file" in err, f"missing file: exit {rc}", out + err)
    txt = os.path.join(d, "text.h5")
    with open(txt, "w") as fh:
        fh.write("not hdf5\n")
    rc, out, err = tool(script, txt)
    expect(rc == 1 and "not an HDF5 file" in err, f"text file: exit {rc}", out + err)
    plain = os.path.join(d, "notvesph.h5")
    with h5py.File(plain, "w") as f:
        for k, v in not_vesph_attrs.items():
            f.attrs[k] = v
    rc, out, err = tool(script, plain)
    expect(rc == 1 and "not a vesph output" in err, f"not vesph: exit {rc}", out + err)


# -------------------------------------------------------------------- tests
def make_tests(tmp):
    T = []

    def t(fn):
        T.append((fn.__name__, fn))
        return fn

    # ---- analytic solution
    @t
    def analytic_initial_and_walls():
        y = np.linspace(0, H, 41)
        expect(np.all(analytic_velocity(y, 0.0, F, NU, H) == 0.0), "v(y,0) != 0")
        for tt in (1e-4, 0.01, 0.3, 3.0):
            vw = analytic_velocity(np.array([0.0, H]), tt, F, NU, H)
            expect(np.max(np.abs(vw)) < 1e-12 * U_CENTRE, f"wall velocity {vw} at t={tt}")
        # lower wall offset y0
        v1 = analytic_velocity(0.3e-3, 0.05, F, NU, H)
        v2 = analytic_velocity(0.3e-3 - 1.0, 0.05, F, NU, H, y0=-1.0)
        expect(abs(v1 - v2) < 1e-15, "y0 shift not honoured")
        expect(isinstance(v1, float), "scalar input must give a float")

    @t
    def analytic_limits():
        y = np.linspace(0, H, 41)
        steady = F / (2 * NU) * y * (H - y)
        v = analytic_velocity(y, 50.0, F, NU, H)      # 50 diffusion times
        expect(np.max(np.abs(v - steady)) < 1e-12 * U_CENTRE, "steady limit wrong")
        vc = analytic_velocity(H / 2, 1e-4, F, NU, H)   # early: v ~ F t in the core
        expect(abs(vc - F * 1e-4) < 1e-9 * F * 1e-4, f"short-time limit {vc} vs {F * 1e-4}")
        # steady centreline value
        expect(abs(analytic_velocity(H / 2, 1e3, F, NU, H) - U_CENTRE) < 1e-15,
               "centreline value")

    @t
    def analytic_satisfies_pde():
        y = np.linspace(0.05e-3, 0.95e-3, 19)
        for tt in (0.01, 0.0225, 0.1125):
            dt, dy = 1e-5 * tt / 0.01, 2e-6
            dvdt = (analytic_velocity(y, tt + dt, F, NU, H)
                    - analytic_velocity(y, tt - dt, F, NU, H)) / (2 * dt)
            d2v = (analytic_velocity(y + dy, tt, F, NU, H) - 2 * analytic_velocity(y, tt, F, NU, H)
                   + analytic_velocity(y - dy, tt, F, NU, H)) / dy ** 2
            res = np.max(np.abs(dvdt - NU * d2v - F)) / F
            expect(res < 1e-4, f"PDE residual {res:.2e} at t={tt}")

    # ---- poiseuille_check
    good = os.path.join(tmp, "good2d")
    h5_good = write_channel_case(good)

    @t
    def poiseuille_exact_profile_passes():
        csv_path = os.path.join(tmp, "p.csv")
        png = os.path.join(tmp, "p.png")
        rc, out, err = tool("poiseuille_check.py", h5_good, "--csv", csv_path, "--png", png)
        expect(rc == 0, f"exit {rc}", out + err)
        expect("RESULT: PASS" in out, "no PASS line", out)
        rows = open(csv_path).read().strip().splitlines()
        expect(rows[0].startswith("frame,time_s,step,n_fluid,error_percent,"
                                  "max_density_deviation,fluid_mass,mass_drift"), rows[0])
        expect(len(rows) == 1 + 4, f"{len(rows) - 1} CSV rows, expected 4 (t > 0)")
        for r in rows[1:]:
            c = r.split(",")
            expect(float(c[4]) < 1e-9, f"error {c[4]} % not ~0")
            expect(abs(float(c[7])) < 1e-15, f"mass drift {c[7]}")
            expect(4e-5 < float(c[5]) < 1e-3, f"density deviation {c[5]}")
        with open(png, "rb") as fh:
            expect(fh.read(8) == b"\x89PNG\r\n\x1a\n", "PNG not written")

    @t
    def fixed_length_string_attributes():
        d = os.path.join(tmp, "fixedstr")
        h5 = write_channel_case(d, fixed_strings=True)
        with h5py.File(h5, "r") as f:
            expect(isinstance(f.attrs["scene"], bytes), "test setup: scene not fixed-length")
        rc, out, err = tool("poiseuille_check.py", h5)
        expect(rc == 0, f"poiseuille_check exit {rc}", out + err)
        rc, out, err = tool("check_output.py", d)
        expect(rc == 0, f"check_output exit {rc}", out + err)

    @t
    def poiseuille_times_selection():
        csv_path = os.path.join(tmp, "p2.csv")
        rc, out, err = tool("poiseuille_check.py", h5_good, "--times", "0.045", "0.5",
                            "--csv", csv_path)
        expect(rc == 0, f"exit {rc}", out + err)
        rows = open(csv_path).read().strip().splitlines()[1:]
        times = sorted(float(r.split(",")[1]) for r in rows)
        expect(times == [0.045, 0.5], f"checked times {times}")

    @t
    def poiseuille_missing_time_fails():
        rc, out, err = tool("poiseuille_check.py", h5_good, "--times", "0.3")
        expect(rc == 1 and "no frame at requested time 0.3" in err, f"exit {rc}", out + err)

    @t
    def poiseuille_velocity_error_detected():
        d = os.path.join(tmp, "perturbed")
        h5 = write_channel_case(d, perturb=(3, 0.03 * U_CENTRE))   # 3 % at frame 000003
        rc, out, err = tool("poiseuille_check.py", h5)
        expect(rc == 1, f"exit {rc}", out + err)
        expect("frame 000003" in err and "velocity error 3" in err, "frame not named", err)
        expect(err.count("FAIL: frame") == 1, "only frame 000003 should fail", err)
        rc, out, err = tool("poiseuille_check.py", h5, "--tolerance", "0.05")
        expect(rc == 0, f"3 % error must pass a 5 % tolerance (exit {rc})", out + err)

    @t
    def poiseuille_mass_drift_detected():
        d = os.path.join(tmp, "massdrift")
        h5 = write_channel_case(d, mass_change=(2, 1e-6))
        rc, out, err = tool("poiseuille_check.py", h5)
        expect(rc == 1 and "frame 000002" in err and "mass drift" in err, f"exit {rc}",
               out + err)

    # ---- check_output: good files
    @t
    def check_output_good_2d_dir():
        rc, out, err = tool("check_output.py", good)
        expect(rc == 0 and "RESULT: OK" in out, f"exit {rc}", out + err)
        expect("valid against" in out, "DTD validation not reported", out)
        expect("UInt\" Precision=\"8\"" in out, "UInt/8 ParaView warning missing", out)

    @t
    def check_output_good_h5_with_xdmf_option():
        d = os.path.join(tmp, "altxdmf")
        shutil.copytree(good, d)
        alt = os.path.join(d, "other_name.xdmf")
        os.rename(os.path.join(d, "poiseuille_newtonian.xdmf"), alt)
        rc, out, err = tool("check_output.py", os.path.join(d, "poiseuille_newtonian.h5"),
                            "--xdmf", alt)
        expect(rc == 0, f"exit {rc}", out + err)

    @t
    def check_output_good_3d_int64_ids():
        d = os.path.join(tmp, "good3d")
        write_3d_case(d, uint64_type=("Int", 8))
        rc, out, err = tool("check_output.py", d)
        expect(rc == 0 and "RESULT: OK" in out, f"exit {rc}", out + err)
        expect("Precision=\"8\" (accepted" in out, "Int/8-for-uint64 note missing", out)

    # ---- check_output: broken files
    def broken_h5(label, mutate, needles):
        def test():
            d = os.path.join(tmp, "broken_" + label)
            h5 = write_channel_case(d)
            with h5py.File(h5, "a") as f:
                mutate(f)
            rc, out, err = tool("check_output.py", d)
            expect(rc == 1, f"exit {rc}, expected 1", out + err)
            for n in needles:
                expect(n in out, f"message {n!r} missing", out)
        test.__name__ = "check_output_catches_" + label
        T.append((test.__name__, test))

    def set_kind_int32(f):
        g = f["frames/000001"]
        k = g["kind"][...]
        del g["kind"]
        g["kind"] = k.astype(np.int32)

    def position_3cols(f):
        g = f["frames/000002"]
        p = g["position"][...]
        del g["position"]
        g["position"] = np.column_stack([p, np.zeros(len(p))])

    def several(f):
        del f["frames/000003/pressure"]
        del f.attrs["kernel"]
        f.attrs["format"] = "vesph-0"
        f["frames/000004/density"][5] = np.nan
        del f["diagnostics/dt"]

    def bad_kind_and_dup_id(f):
        k = f["frames/000001/kind"][...]
        k[0] = 7
        f["frames/000001/kind"][...] = k
        ids = f["frames/000002/id"][...]
        ids[1] = ids[0]
        f["frames/000002/id"][...] = ids

    def dim_as_float(f):
        f.attrs["dim"] = 2.0
        f.attrs["dx"] = np.float32(DX)
        f["frames/000001"].attrs["time"] = np.float32(0.0225)

    broken_h5("wrong_dtype", set_kind_int32,
              ["/frames/000001/kind: dtype int32, expected uint8",
               "is int32 but the DataItem says NumberType=\"UChar\""])
    broken_h5("wrong_shape", position_3cols,
              ["/frames/000002/position: shape [1000, 3], expected [1000, 2]",
               "has shape [1000, 3] but Dimensions = \"1000 2\""])
    broken_h5("missing_items", several,
              ["/frames/000003/pressure: missing", "'kernel' is missing",
               "format = 'vesph-0'", "/frames/000004/density: contains non-finite",
               "/diagnostics/dt: missing", "/frames/000003/pressure does not exist"])
    broken_h5("bad_values", bad_kind_and_dup_id,
              ["kind: invalid values [7]", "/frames/000002/id: ids are not unique"])
    broken_h5("attr_types", dim_as_float,
              ["dim = 2.0", "dx has type float32",
               "/frames/000001: attribute time has type float32"])

    def broken_xdmf(label, edit, needles, regex=False):
        def test():
            d = os.path.join(tmp, "brokenx_" + label)
            write_channel_case(d)
            p = os.path.join(d, "poiseuille_newtonian.xdmf")
            text = open(p).read()
            new = edit(text)
            expect(new != text, "edit did not change the XDMF")
            with open(p, "w") as fh:
                fh.write(new)
            rc, out, err = tool("check_output.py", d)
            expect(rc == 1, f"exit {rc}, expected 1", out + err)
            for n in needles:
                ok = re.search(n, out) if regex else n in out
                expect(ok, f"message {n!r} missing", out)
        test.__name__ = "check_output_catches_xdmf_" + label
        T.append((test.__name__, test))

    broken_xdmf("not_well_formed", lambda s: s.replace("</Geometry>", "</Geometri>", 1),
                ["not well-formed XML"])
    broken_xdmf("dtd_enum", lambda s: s.replace('CollectionType="Temporal"',
                                                'CollectionType="Temporal" GridType2="x"')
                .replace('GridType="Uniform"', 'GridType="Temporal"', 1),
                ["xmllint --dtdvalid", "GridType2", "Value \"Temporal\" for attribute GridType"])
    broken_xdmf("dtd_unknown_element", lambda s: s.replace("<Time ", "<Tme ", 1),
                ["No declaration for element Tme", "no <Time Value=...>"])
    broken_xdmf("dims_mismatch",
                lambda s: s.replace('Dimensions="1000 2" NumberType="Float" Precision="8" '
                                    'Format="HDF">poiseuille_newtonian.h5:/frames/000001/velocity',
                                    'Dimensions="1000 3" NumberType="Float" Precision="8" '
                                    'Format="HDF">poiseuille_newtonian.h5:/frames/000001/velocity'),
                ["/frames/000001/velocity has shape [1000, 2] but Dimensions = \"1000 3\""])
    broken_xdmf("precision_mismatch",
                lambda s: s.replace('NumberType="Float" Precision="8" Format="HDF">'
                                    'poiseuille_newtonian.h5:/frames/000002/density',
                                    'NumberType="Float" Precision="4" Format="HDF">'
                                    'poiseuille_newtonian.h5:/frames/000002/density'),
                ["/frames/000002/density is float64 but the DataItem says NumberType=\"Float\" "
                 "Precision=\"4\""])
    broken_xdmf("number_of_elements", lambda s: s.replace('NumberOfElements="1000"',
                                                          'NumberOfElements="999"', 1),
                ["Topology NumberOfElements = 999 but frame 000000 has N = 1000"])
    broken_xdmf("missing_dataset", lambda s: s.replace("/frames/000004/pressure",
                                                       "/frames/000004/presure"),
                ["/frames/000004/presure does not exist"])
    broken_xdmf("time_value", lambda s: s.replace('<Time Value="0.1125"/>',
                                                  '<Time Value="0.11249"/>'),
                ["Time Value 0.11249 != frame 000003 time 0.1125"])
    broken_xdmf("missing_frame", lambda s: re.sub(
        r'   <Grid Name="frame_000004".*?</Grid>\n', "", s, flags=re.S),
        ["frame 000004 of the HDF5 file has no Grid"])
    broken_xdmf("geometry_type", lambda s: s.replace('GeometryType="XY"', 'GeometryType="XYZ"', 1),
                ["GeometryType = XYZ, expected XY"])

    @t
    def check_output_time_precision():
        d = os.path.join(tmp, "timeprec")
        write_channel_case(d, times=[0.0, 1.0 / 3.0], time_fmt=lambda v: f"{v:g}")
        rc, out, err = tool("check_output.py", d)
        expect(rc == 1 and "Time Value 0.333333 != frame 000001 time" in out, f"exit {rc}",
               out + err)

    @t
    def check_output_missing_summary():
        d = os.path.join(tmp, "nosummary")
        write_channel_case(d)
        os.remove(os.path.join(d, "summary.json"))
        rc, out, err = tool("check_output.py", d)
        expect(rc == 1 and "summary.json is missing" in out, f"exit {rc}", out + err)

    @t
    def check_output_missing_xdmf():
        d = os.path.join(tmp, "noxdmf")
        write_channel_case(d)
        os.remove(os.path.join(d, "poiseuille_newtonian.xdmf"))
        rc, out, err = tool("check_output.py", d)
        expect(rc == 1 and "does not exist" in out, f"exit {rc}", out + err)

    # ---- startup_channel_profiles
    def prof(h5, *args, png=False):
        od = os.path.join(tmp, "prof_out")
        extra = () if png else ("--no-png",)
        rc, out, err = tool("startup_channel_profiles.py", h5, "--out-dir", od, *extra, *args)
        return rc, out, err, od

    def close(a, b, scale, what):
        expect(abs(float(a) - float(b)) <= 1e-12 * scale, f"{what}: {a} != {b}")

    SCALES = {"vx": SU_UC, "txx": SU_A, "txy": SU_C, "tyy": 1e-8, "n1": SU_A, "y": H}
    CSVCOL = {"vx": "vx_m_s", "txx": "Txx_Pa", "txy": "Txy_Pa", "tyy": "Tyy_Pa",
              "n1": "N1_Pa", "y": "y_m"}

    def check_profile(rows, info, frame, station, cols, stress=True, label=""):
        sel = [r for r in rows if abs(float(r["station_x_m"]) - station) < 1e-15
               and float(r["time_s"]) == SU_TIMES[frame]]
        expect(len(sel) == info["ny"], f"{label}: {len(sel)} rows at x = {station}, "
               f"t = {SU_TIMES[frame]}, expected {info['ny']}")
        expect(all(r["frame"] == f"{frame:06d}" for r in sel), f"{label}: frame column")
        ref = su_expected_profile(info, frame, cols)
        sel.sort(key=lambda r: float(r["y_m"]))
        for j, (r, e) in enumerate(zip(sel, ref)):
            expect(int(r["count"]) == e["count"],
                   f"{label}: row {j} count {r['count']}, expected {e['count']}")
            for k in (("y", "vx", "txx", "txy", "tyy", "n1") if stress else ("y", "vx")):
                close(r[CSVCOL[k]], e[k], SCALES[k], f"{label}: row {j} {k}")
            close(r["Y"], (e["y"] - info["yc"]) / info["a"], 1.0, f"{label}: row {j} Y")

    def check_centreline(csv_path, info, centre_rows, stress=True):
        rows = read_csv_rows(csv_path)
        expect(len(rows) == len(SU_TIMES), f"{len(rows)} centreline rows")
        for i, r in enumerate(rows):
            t, x, y, vx, txx, txy, tyy, row, col = info["frames"][i]
            m = np.isin(row, centre_rows)
            expect(float(r["time_s"]) == SU_TIMES[i] and int(r["step"]) == 10 * i,
                   f"centreline time/step {r}")
            expect(int(r["n_centre"]) == int(m.sum()),
                   f"frame {i}: n_centre {r['n_centre']}, expected {int(m.sum())}")
            close(r["vx_centre_m_s"], vx[m].mean(), SU_UC, f"frame {i} centreline v_x")
            if stress:
                close(r["max_abs_Txy_Pa"], np.max(np.abs(txy)), SU_C, f"frame {i} max|Txy|")
                close(r["max_N1_Pa"], np.max(txx - tyy), SU_A, f"frame {i} max N1")
            else:
                expect("max_N1_Pa" not in r, "stress column without extra_stress")

    h5_su, info_su = write_startup_case(os.path.join(tmp, "su"))

    @t
    def profiles_cluster_rows_unit():
        rng = np.random.default_rng(3)
        rows = np.repeat(np.arange(10), 7)
        y = (rows + 0.5) * DX + 0.2 * DX * rng.uniform(-1, 1, len(rows))
        perm = rng.permutation(len(y))
        lab, n, method = cluster_rows(y[perm], DX, 0.0)
        expect(n == 10 and method == "clustered", f"{n} rows, {method}")
        expect(np.array_equal(lab, rows[perm]), "row labels wrong")
        y2 = (rows + 0.5) * DX + 0.45 * DX * rng.uniform(-1, 1, len(rows))
        lab, n, method = cluster_rows(y2, DX, 0.0)
        expect(method.startswith("lattice bins") and n == 10, f"{n} rows, {method}")
        expect(np.array_equal(lab, rows), "fallback row labels wrong")
        # a row shifted by more than dx/2 from the lattice is still one cluster
        lab, n, method = cluster_rows(rows * DX + 0.7 * DX, DX, 0.0)
        expect(n == 10 and method == "clustered", f"shifted: {n} rows, {method}")

    @t
    def profiles_exact_default_station_and_time():
        rc, out, err, od = prof(h5_su)
        expect(rc == 0, f"exit {rc}", out + err)
        for needle in ("rows: clustered in 5 frame(s)", "extra_stress present",
                       "model: oldroyd_b", "y_c = 0.0005 m, a = 0.0005 m", "(periodic)"):
            expect(needle in out, f"{needle!r} missing", out)
        rows = read_csv_rows(os.path.join(od, "startup_synth_profiles.csv"))
        expect(list(rows[0].keys()) == ["station_x_m", "time_s", "frame", "y_m", "Y",
                                        "vx_m_s", "Txx_Pa", "Txy_Pa", "Tyy_Pa", "N1_Pa",
                                        "count"], f"header {list(rows[0].keys())}")
        expect(len(rows) == 40, f"{len(rows)} rows: default = one station, last frame")
        # middle x = 10 dx lies half-way between lattice columns 9 and 10
        check_profile(rows, info_su, 4, 10 * DX, [9, 10], label="default")
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info_su, [19, 20])

    @t
    def profiles_stations_bins_periodic_times():
        rc, out, err, od = prof(h5_su, "--stations", f"0,{3.5 * DX!r}", "--times", "0.1,0.26")
        expect(rc == 0, f"exit {rc}", out + err)
        expect("time 0.26 s: nearest frame 000003 at t = 0.3 s" in out, "nearest-frame note",
               out)
        rows = read_csv_rows(os.path.join(od, "startup_synth_profiles.csv"))
        expect(len(rows) == 2 * 2 * 40, f"{len(rows)} rows")
        for fr in (1, 3):
            check_profile(rows, info_su, fr, 0.0, [0, SU_NX - 1], label="x=0 periodic")
            check_profile(rows, info_su, fr, 3.5 * DX, [3], label="x=3.5dx")
        rc, out, err, od = prof(h5_su, "--stations", f"0,{3.5 * DX!r}", "--times", "0.2",
                                "--bin-width", repr(3 * DX))
        expect(rc == 0, f"exit {rc}", out + err)
        rows = read_csv_rows(os.path.join(od, "startup_synth_profiles.csv"))
        check_profile(rows, info_su, 2, 0.0, [18, 19, 0, 1], label="x=0 bin 3dx")
        check_profile(rows, info_su, 2, 3.5 * DX, [2, 3, 4], label="x=3.5dx bin 3dx")
        rc, out, err, od = prof(h5_su, "--all-times", "--prefix", "every")
        expect(rc == 0, f"exit {rc}", out + err)
        rows = read_csv_rows(os.path.join(od, "every_profiles.csv"))
        expect(len(rows) == 5 * 40, f"--all-times: {len(rows)} rows")
        for fr in range(5):
            check_profile(rows, info_su, fr, 10 * DX, [9, 10], label=f"all-times {fr}")

    @t
    def profiles_odd_rows_centre_row_only():
        h5, info = write_startup_case(os.path.join(tmp, "su_odd"), ny=39)
        rc, out, err, od = prof(h5)
        expect(rc == 0, f"exit {rc}", out + err)
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info, [19])
        check_profile(read_csv_rows(os.path.join(od, "startup_synth_profiles.csv")), info, 4,
                      10 * DX, [9, 10], label="odd")

    @t
    def profiles_disordered_rows_fall_back_to_lattice_bins():
        h5, info = write_startup_case(os.path.join(tmp, "su_dis"), jitter=0.45)
        rc, out, err, od = prof(h5)
        expect(rc == 0, f"exit {rc}", out + err)
        expect("rows: lattice bins (rows too disordered to cluster) in 5 frame(s)" in out,
               "fallback not reported", out)
        check_profile(read_csv_rows(os.path.join(od, "startup_synth_profiles.csv")), info, 4,
                      10 * DX, [9, 10], label="disordered")
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info, [19, 20])

    @t
    def profiles_newtonian_velocity_only():
        h5, info = write_startup_case(os.path.join(tmp, "su_newt"), stress=False)
        rc, out, err, od = prof(h5, png=True)
        expect(rc == 0, f"exit {rc}", out + err)
        expect("no extra_stress in the frames" in out and "Newtonian" in out,
               "missing-stress note", out)
        rows = read_csv_rows(os.path.join(od, "startup_synth_profiles.csv"))
        expect(list(rows[0].keys()) == ["station_x_m", "time_s", "frame", "y_m", "Y", "vx_m_s",
                                        "count"], f"header {list(rows[0].keys())}")
        check_profile(rows, info, 4, 10 * DX, [9, 10], stress=False, label="newtonian")
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info, [19, 20],
                         stress=False)
        for f in ("startup_synth_centreline.png", "startup_synth_profiles.png"):
            with open(os.path.join(od, f), "rb") as fh:
                expect(fh.read(8) == b"\x89PNG\r\n\x1a\n", f"{f} not written")

    @t
    def profiles_3d_stress_components():
        h5, info = write_startup_case(os.path.join(tmp, "su_3d"), dim=3)
        rc, out, err, od = prof(h5)
        expect(rc == 0, f"exit {rc}", out + err)
        check_profile(read_csv_rows(os.path.join(od, "startup_synth_profiles.csv")), info, 4,
                      10 * DX, [9, 10], label="3d")
        check_centreline(os.path.join(od, "startup_synth_centreline.csv"), info, [19, 20])

    @t
    def profiles_png_and_summary():
        od = os.path.join(tmp, "prof_png")
        rc, out, err = tool("startup_channel_profiles.py", h5_su, "--out-dir", od,
                            "--prefix", "run1", "--times", "0.1,0.4", "--stations",
                            f"{2.5 * DX!r},{10 * DX!r}")
        expect(rc == 0, f"exit {rc}", out + err)
        for f in ("run1_centreline.csv", "run1_profiles.csv", "run1_centreline.png",
                  "run1_profiles.png"):
            expect(f"wrote {os.path.join(od, f)}" in out, f"{f} not reported", out)
            expect(os.path.getsize(os.path.join(od, f)) > 0, f"{f} empty")
        # summary: one line per station and time with rows, particles and counts
        expect(re.search(r"\n\s+6\.25e-05\s+0\.1\s+000001\s+40\s+40\s+1\s", out),
               "summary line for x = 2.5 dx, t = 0.1", out)
        expect(re.search(r"\n\s+0\.00025\s+0\.4\s+000004\s+40\s+80\s+2\s", out),
               "summary line for x = 10 dx, t = 0.4", out)

    @t
    def profiles_errors():
        def bad(args, rc_expected, needle):
            rc, out, err = tool("startup_channel_profiles.py", *args, "--out-dir",
                                os.path.join(tmp, "prof_err"), "--no-png")
            expect(rc == rc_expected, f"{args}: exit {rc}, expected {rc_expected}", out + err)
            expect(needle in err, f"{args}: message {needle!r} missing", out + err)

        bad([os.path.join(tmp, "nonexistent.h5")], 1, "no such file")
        txt = os.path.join(tmp, "not_hdf5.h5")
        with open(txt, "w") as fh:
            fh.write("hello\n")
        bad([txt], 1, "is not an HDF5 file")
        other = os.path.join(tmp, "other.h5")
        with h5py.File(other, "w") as f:
            f["data"] = np.zeros(3)
        bad([other], 1, "is not a vesph output: root attribute 'format' is missing")
        h5, _ = write_startup_case(os.path.join(tmp, "su_nofluid"), no_fluid=True)
        bad([h5], 1, "has no fluid particles")
        bad([h5_su, "--stations", repr(30 * DX)], 2,
            "station x = 0.00075 m is outside the channel, x in [0, 0.0005] m")
        bad([h5_su, "--stations=-1e-5"], 2, "is outside the channel")
        bad([h5_su, "--times", "0.5"], 2, "time 0.5 s is outside the output range [0, 0.4] s")
        bad([h5_su, "--stations", "a,b"], 2, "expected comma-separated numbers")
        bad([h5_su, "--times", "0.1", "--all-times"], 2, "not allowed with argument")
        bad([h5_su, "--bin-width", "0"], 2, "--bin-width must be > 0")

    # ---- ParaView (optional)
    @t
    def paraview_reads_synthetic_xdmf():
        probe = subprocess.run([PY, "-c", "import paraview.simple"], capture_output=True)
        if probe.returncode != 0:
            print("      (skipped: ParaView Python modules not installed)")
            return
        d = os.path.join(tmp, "pv")
        write_channel_case(d, times=[0.0, 0.0225, 0.5], uint64_type=("Int", 8))
        write_3d_case(d, uint64_type=("Int", 8))
        for name, npts, arrays in (
                ("poiseuille_newtonian", 1000,
                 {"velocity": 2, "density": 1, "mass": 1, "pressure": 1, "id": 1, "kind": 1}),
                ("box3d", 64, {"velocity": 3, "extra_stress": 6, "free_surface": 1, "id": 1})):
            x = os.path.join(d, name + ".xdmf")
            rc, out, err = tool("paraview_check.py", x, "--json", x + ".json")
            expect(rc == 0, f"paraview_check exit {rc}", out + err)
            res = json.load(open(x + ".json"))
            expect(len(res["steps"]) == len(res["timesteps"]) >= 3, "time steps", out)
            for st in res["steps"]:
                expect(st["points"] == npts, f"{st['points']} points", out)
                for a, nc in arrays.items():
                    expect(a in st["arrays"] and st["arrays"][a]["components"] == nc,
                           f"array {a} components", out)
            last = res["steps"][-1]
            if name == "box3d":
                expect(last["arrays"]["id"]["range"][0] == 2 ** 33, "64-bit ids mangled", out)
                expect(last["arrays"]["id"]["type"] in ("vtkLongArray", "vtkLongLongArray",
                                                        "vtkTypeInt64Array"), "id type", out)
            else:
                vmax = last["arrays"]["velocity"]["component_ranges"][0][1]
                expect(abs(vmax - analytic_velocity(H / 2 - DX / 2, 0.5, F, NU, H)) < 1e-12,
                       f"velocity max {vmax}", out)
                expect(abs(last["bounds"][3] - (H + 5 * DX - DX / 2)) < 1e-12, "y bounds", out)

    return T


# ------------------------------------------------------------- XPP (tools/xpp_steady_shear.py)
XPP_SCENE = """\
name = "startup_channel_xpp"
dimension = 2
[domain]
min = [0.0, -1.25e-4]
max = [1.0e-4, 1.125e-3]
periodic = [true, false]
[particles]
spacing = 2.5e-5
[fluid]
density = 1000.0
viscosity = 2.0e-4
[[blocks]]
kind = "fluid"
min = [0.0, 0.0]
max = [1.0e-4, 1.0e-3]
[[blocks]]
kind = "wall"
min = [0.0, -1.25e-4]
max = [1.0e-4, 0.0]
[effects.viscosity]
[effects.xpp]
polymer_viscosity = 8.0e-4
backbone_relaxation_time = 0.5
relaxation_ratio = 3.0
arms = 4
anisotropy = 0.15
[effects.body_force]
acceleration = [4.1e-3, 0.0]
"""


def write_xpp_channel(path, t_end=4.0, dt_frame=0.25, n1d=48, perturb=None):
    """A synthetic XPP start-up channel (4 x 40 fluid particles on a 2.5e-5 m lattice, one wall
    row) whose fields are the 1-D start-up of xpp_steady_shear at n1d cells, interpolated to
    the particles (T_xy = eta_s dv/dy + tau_xy). perturb(k, frame) may alter frame k."""
    import tomllib
    import xpp_steady_shear as X
    scene = tomllib.loads(XPP_SCENE)
    p, rho, F, y0, y1 = X.scene_parameters(scene)
    times = np.arange(0.0, t_end + 1e-9, dt_frame)
    yc, v, tau, yf = X.startup_1d(p, rho, F, y0, y1, times, n=n1d)
    xs = (np.arange(4) + 0.5) * 2.5e-5
    ys = (np.arange(40) + 0.5) * 2.5e-5
    Xg, Yg = np.meshgrid(xs, ys)
    pos = np.column_stack([Xg.ravel(), Yg.ravel()])
    wall = np.column_stack([xs, np.full(4, -1.25e-5)])
    pos = np.vstack([pos, wall])
    kind = np.concatenate([np.zeros(160, np.uint8), np.ones(4, np.uint8)])
    y = pos[:160, 1]
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "vesph-1"
        f.attrs["dim"] = np.int64(2)
        f.attrs["scene"] = XPP_SCENE
        f.attrs["dx"] = np.float64(2.5e-5)
        for k, t in enumerate(times):
            vk = np.concatenate([[-v[k][0]], v[k], [-v[k][-1]]])
            g_faces = np.diff(vk) / (yc[1] - yc[0])
            vel = np.zeros((164, 2))
            vel[:160, 0] = np.interp(y, yc, v[k])
            T = np.zeros((164, 3))
            T[:160, 0] = np.interp(y, yf, tau[k, 0])
            T[:160, 1] = np.interp(y, yf, p.eta_s * g_faces + tau[k, 1])
            T[:160, 2] = np.interp(y, yf, tau[k, 2])
            zz = np.zeros(164)
            zz[:160] = np.interp(y, yf, tau[k, 3])
            fr = {"velocity": vel, "extra_stress": T, "extra_stress_zz": zz}
            if perturb:
                perturb(k, len(times), fr)
            g = f.create_group(f"frames/{k:06d}")
            g.attrs["time"] = np.float64(t)
            g.attrs["step"] = np.int64(k)
            g.create_dataset("position", data=pos)
            g.create_dataset("kind", data=kind)
            for name, arr in fr.items():
                g.create_dataset(name, data=arr)
    return path


def make_xpp_tests(tmp):
    import xpp_steady_shear as X
    T = []

    def t(fn):
        T.append((fn.__name__, fn))
        return fn

    P = X.Xpp(G=1.6e-3, lam_b=0.5, r=3.0, q=4, alpha=0.15, eta_s=2e-4)

    @t
    def xpp_small_rate_limit_is_oldroyd_b():
        # Wi = 1e-3: tau_xy = eta_p gdot, N1 = 2 eta_p lambda_0b gdot^2 (Oldroyd-B/UCM),
        # N2 = -alpha eta_p lambda_0b gdot^2, to O(Wi^2)
        g = 1e-3 / P.lam_b
        x = X.steady_shear(g, P)
        expect(abs(x[1] / (P.eta_p * g) - 1) < 1e-5, f"eta {x[1]/g} vs eta_p {P.eta_p}")
        expect(abs((x[0] - x[2]) / (2 * P.eta_p * P.lam_b * g * g) - 1) < 1e-4, f"Psi1 {x}")
        expect(abs((x[2] - x[3]) / (-P.alpha * P.eta_p * P.lam_b * g * g) - 1) < 1e-3, f"Psi2 {x}")
        # and at Wi = 2 it is clearly not Oldroyd-B (shear thinning)
        x = X.steady_shear(2 / P.lam_b, P)
        expect(x[1] < 0.8 * P.eta_p * 2 / P.lam_b, "no shear thinning at Wi = 2")

    @t
    def xpp_ode_and_algebraic_routes_agree():
        for p in (P, X.Xpp(1.0, 1.0, 2.0, 2, 0.0), X.Xpp(1.0, 1.0, 5.0, 10, 0.3)):
            for wi in (0.3, 2.0, 8.0):
                a = X.steady_shear(wi / p.lam_b, p)
                b = X.steady_shear_ode(wi / p.lam_b, p)
                expect(np.max(np.abs(a - b)) < 1e-8 * np.max(np.abs(a)), f"Wi {wi}: {a} vs {b}")
                r = X.shear_residual(a, wi / p.lam_b, p)
                expect(np.max(np.abs(r)) * p.lam_b < 1e-10 * p.G, f"residual {r}")
                if p.alpha == 0:
                    expect(abs(a[2] - a[3]) < 1e-12 * p.G, "N2 != 0 with alpha = 0")
                expect(abs(a[3]) > 1e-3 * abs(a[2]), "tau_zz = 0")

    @t
    def xpp_flow_curve_inversion_and_channel_velocity():
        curve = X.FlowCurve(P, 10.0)
        for T_ in (1e-6, 3e-4, 1.2e-3, 2.5e-3):
            g = curve.rate_at_stress(T_)
            x = X.steady_shear(float(g), P)
            expect(abs(P.eta_s * g + x[1] - T_) < 1e-6 * T_, f"stress at the inverted rate, T = {T_}")
            expect(np.max(np.abs(curve.tau_at_rate(g) - x)) < 1e-6 * np.max(np.abs(x)), "tau at rate")
        from scipy.integrate import quad
        rho, F, a = 1000.0, 4.1e-3, 5e-4
        ref = X.channel_reference(np.array([0.3e-3, a]), P, rho, F, 0.0, 2 * a, curve=curve)
        for k, yy in enumerate((0.3e-3, a)):
            vq = quad(lambda s: float(curve.rate_at_stress(-rho * F * (s - a))), 0, yy, limit=200)[0]
            expect(abs(ref["v"][k] - vq) < 1e-6 * vq, f"v({yy}) {ref['v'][k]} vs {vq}")

    @t
    def xpp_startup_1d_converges_to_the_steady_channel():
        rho, F, a = 1000.0, 4.1e-3, 5e-4
        ref = X.channel_reference(np.array([a]), P, rho, F, 0.0, 2 * a)
        yc, v, tau, yf = X.startup_1d(P, rho, F, 0.0, 2 * a, [0.0, 20 * P.lam_b], n=32)
        vc = np.interp(a, yc, v[-1])
        expect(abs(vc / ref["v"][0] - 1) < 2e-3, f"1-D steady centreline {vc} vs {ref['v'][0]}")
        expect(np.max(np.abs(tau[-1, :, 0] - ref["curve"].tau_at_rate(ref["curve"].rate_at_stress(rho * F * a))))
               < 2e-3 * P.G, "1-D wall stresses")

    good = os.path.join(tmp, "xpp_good.h5")

    @t
    def xpp_check_passes_on_the_1d_startup():
        write_xpp_channel(good)
        rc, out, err = tool("xpp_steady_shear.py", "check", good, "--transient", "--n1d", "32",
                            "--csv", good + ".csv", "--png", good + ".png",
                            "--transient-csv", good + ".t.csv", "--transient-png", good + ".t.png")
        expect(rc == 0 and "RESULT: PASS" in out, f"exit {rc}", out + err)
        for f_ in (".csv", ".png", ".t.csv", ".t.png"):
            expect(os.path.getsize(good + f_) > 0, f"no {f_}")
        expect("tau_zz" in out and "N2" in out, "tau_zz/N2 not compared", out)

    @t
    def xpp_check_fails_on_a_wrong_tau_zz():
        def bad(k, n, fr):
            if k == n - 1:
                fr["extra_stress_zz"] *= 1.05
        path = write_xpp_channel(os.path.join(tmp, "xpp_zz.h5"), perturb=bad)
        rc, out, err = tool("xpp_steady_shear.py", "check", path, "--n1d", "32")
        expect(rc == 1 and re.search(r"tau_zz .*FAIL", out) is not None, f"exit {rc}", out + err)

    @t
    def xpp_check_fails_on_an_oscillating_startup():
        def bad(k, n, fr):
            if 2 <= k < n - 1:
                fr["velocity"][:, 0] *= 1.0 + 0.01 * (-1) ** k
        path = write_xpp_channel(os.path.join(tmp, "xpp_osc.h5"), perturb=bad)
        rc, out, err = tool("xpp_steady_shear.py", "check", path, "--transient", "--n1d", "32")
        expect(rc == 1 and re.search(r"centreline velocity .*FAIL", out) is not None, f"exit {rc}", out + err)
        rc, out, err = tool("xpp_steady_shear.py", "check", path, "--n1d", "32")
        expect(rc == 0, "the steady check alone should pass", out + err)

    @t
    def xpp_check_fails_before_the_steady_state():
        path = write_xpp_channel(os.path.join(tmp, "xpp_early.h5"), t_end=1.0)
        rc, out, err = tool("xpp_steady_shear.py", "check", path, "--n1d", "32")
        expect(rc == 1 and "not steady" in out, f"exit {rc}", out + err)

    @t
    def xpp_check_rejects_a_scene_without_xpp():
        h5 = write_channel_case(os.path.join(tmp, "xpp_newtonian"))
        rc, out, err = tool("xpp_steady_shear.py", "check", h5)
        expect(rc == 2 and "effects.xpp" in out, f"exit {rc}", out + err)

    return T


# ------------------------------------------------------- drop_measure.py tests
DROP_DX, DROP_RHO = 1.0e-3, 1000.0
DROP_SCENE = """\
name = "{name}"
dimension = {dim}
[domain]
min = {dmin}
max = {dmax}
[particles]
spacing = 1.0e-3
kernel = "cubic"
smoothing_ratio = 1.5
[fluid]
density = 1000.0
viscosity = 0.4
[[blocks]]
kind = "fluid"
{fluid}
[[blocks]]
kind = "wall"
min = {wmin}
max = {wmax}
[effects.continuity]
[time]
end = 0.04
"""


def drop_scene(name="drop_synth", dim=2, shape="disk", wall=True):
    """A drop scene: a disk (sphere) of D = 0.02 m (20 dx) at centre y = 0.015 m (3D: 0.006 m,
    D = 0.008 m), V = -1 m/s, the wall top at y = 0."""
    if dim == 2:
        fluid = ('shape = "disk"\ncentre = [0.0, 0.015]\ndiameter = 0.02\n'
                 'velocity = [0.0, -1.0]')
        if shape == "box":
            fluid = 'min = [-0.01, 0.005]\nmax = [0.01, 0.025]\nvelocity = [0.0, -1.0]'
        s = DROP_SCENE.format(name=name, dim=2, dmin="[-0.06, -0.003]", dmax="[0.06, 0.04]",
                              fluid=fluid, wmin="[-0.05, -0.003]", wmax="[0.05, 0.0]")
    else:
        fluid = ('shape = "sphere"\ncentre = [0.0, 0.006, 0.0]\ndiameter = 0.008\n'
                 'velocity = [0.0, -1.0, 0.0]')
        s = DROP_SCENE.format(name=name, dim=3, dmin="[-0.02, -0.003, -0.02]",
                              dmax="[0.02, 0.02, 0.02]", fluid=fluid,
                              wmin="[-0.02, -0.003, -0.02]", wmax="[0.02, 0.0, 0.02]")
    if not wall:
        s = s[:s.index('[[blocks]]\nkind = "wall"')] + "[effects.continuity]\n"
    return s


def drop_lattice(R=10, centre=(0.0, 0.015), dim=2):
    """Lattice disk (sphere) of radius R dx: the nodes centre + k dx within the radius."""
    k = np.arange(-R, R + 1)
    K = np.stack(np.meshgrid(*([k] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    K = K[np.sum(K * K, axis=1) <= R * R]
    return np.asarray(centre, dtype=float) + K * DROP_DX, K


def write_drop(path, frames, scene=None, dim=2):
    """frames: list of (time [s], fluid positions [n, dim], optional density factor array or
    scalar). Wall particles: one row at y = -dx/2. mass = rho dx^dim."""
    scene = scene or drop_scene(dim=dim)
    if dim == 2:
        wx = (np.arange(-40, 40) + 0.5) * DROP_DX
        wall = np.column_stack([wx, np.full(len(wx), -0.5 * DROP_DX)])
    else:
        wx = (np.arange(-8, 8) + 0.5) * DROP_DX
        X, Z = np.meshgrid(wx, wx)
        wall = np.column_stack([X.ravel(), np.full(X.size, -0.5 * DROP_DX), Z.ravel()])
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "vesph-1"
        f.attrs["dim"] = np.int64(dim)
        f.attrs["scene"] = scene
        f.attrs["dx"] = np.float64(DROP_DX)
        for i, fr in enumerate(frames):
            t, fl = fr[0], np.asarray(fr[1], dtype=float)
            scale = fr[2] if len(fr) > 2 else 1.0
            n, nw = len(fl), len(wall)
            g = f.create_group(f"frames/{i:06d}")
            g.attrs["time"] = np.float64(t)
            g.attrs["step"] = np.int64(10 * i)
            g.create_dataset("position", data=np.vstack([fl, wall]))
            g.create_dataset("velocity", data=np.zeros((n + nw, dim)))
            g.create_dataset("kind", data=np.concatenate([np.zeros(n, np.uint8),
                                                          np.ones(nw, np.uint8)]))
            g.create_dataset("id", data=np.arange(n + nw, dtype=np.uint64))
            rho = np.full(n + nw, DROP_RHO)
            rho[:n] *= scale
            g.create_dataset("density", data=rho)
            g.create_dataset("mass", data=np.full(n + nw, DROP_RHO * DROP_DX ** dim))
    return path


def make_drop_tests(tmp):
    T = []

    def t(fn):
        T.append((fn.__name__, fn))
        return fn

    d = os.path.join(tmp, "drop")
    os.makedirs(d, exist_ok=True)
    dx = DROP_DX
    disk, K = drop_lattice()                 # R = 10 dx: 317 particles, width 20 dx = D
    N = len(disk)

    def measure(path, *args):
        """Run the tool (no PNG unless "--png" is among args); (rc, out, err, CSV rows)."""
        png = "--png" in args
        args = [x for x in args if x != "--png"] + ([] if png else ["--no-png"])
        rc, out, err = tool("drop_measure.py", path, "--out-dir", d, "--prefix",
                            os.path.splitext(os.path.basename(path))[0], *args)
        csvp = os.path.join(d, os.path.splitext(os.path.basename(path))[0] + "_drop.csv")
        rows = read_csv_rows(csvp) if rc in (0, 1) and os.path.exists(csvp) else []
        return rc, out, err, rows

    def near(v, ref, tol=1e-9):
        return abs(float(v) - ref) <= tol * max(1.0, abs(ref))

    @t
    def drop_lattice_disk_width_height_area():
        # frame 0: the disk; 1: translated down by V t; 2: a flattened blob on the wall, bottom
        # row of 30 particles at 0.6 dx, 5 rows of 40 above (contact 29 dx, width 39 dx)
        blob = [np.column_stack([(np.arange(30) - 14.5) * dx, np.full(30, 0.6 * dx)])]
        for j in range(1, 6):
            blob.append(np.column_stack([(np.arange(40) - 19.5) * dx,
                                         np.full(40, (0.6 + j) * dx)]))
        blob = np.vstack(blob)
        h5 = write_drop(os.path.join(d, "lattice.h5"),
                        [(0.0, disk), (0.003, disk - [0.0, 0.003]), (0.0125, blob)])
        rc, out, err, rows = measure(h5, "--png")
        expect(rc == 0 and len(rows) == 3, f"exit {rc}, {len(rows)} rows", out + err)
        r0, r1, r2 = rows
        for r, tvd in zip(rows, (0.0, 0.15, 0.625)):
            expect(near(r["tV_over_D"], tvd), f"tV/D {r['tV_over_D']} != {tvd}")
        expect(near(r0["width_m"], 0.02) and near(r0["width_over_D"], 1.0), f"width {r0}")
        expect(near(r0["height_m"], 0.025) and near(r0["height_over_D"], 1.25), f"height {r0}")
        expect(near(r1["height_over_D"], 1.1) and near(r1["width_over_D"], 1.0)
               and r1["n_contact"] == "0", f"frame 1 {r1}")
        area = N * dx * dx
        expect(near(r0["volume_m2"], area), f"area {r0['volume_m2']} != {area}")
        expect(near(r0["volume_rel_err_disk"], area / (math.pi * 1e-4) - 1, 1e-7),
               f"error vs the disk {r0['volume_rel_err_disk']}")
        expect(float(r0["volume_rel_err_first"]) == 0.0, "error vs the first frame")
        expect(r0["n_contact"] == "0" and float(r0["contact_width_m"]) == 0.0, "contact at t=0")
        expect(r0["clusters"] == "1" and r0["detached"] == "0" and r0["fractured"] == "0",
               f"clusters {r0}")
        expect(near(r0["max_nn_gap_over_dx"], 1.0) and float(r0["void_gap_over_dx"]) <= 1.5,
               f"gaps {r0}")
        expect(near(r2["width_m"], 39 * dx) and near(r2["contact_width_m"], 29 * dx)
               and r2["n_contact"] == "30", f"blob widths {r2}")
        expect(near(r2["height_m"], 5.6 * dx), f"blob height {r2['height_m']}")
        expect(near(r2["volume_rel_err_first"], 230 / N - 1), "blob volume error")
        expect(os.path.getsize(os.path.join(d, "lattice_drop.png")) > 0, "no PNG")
        expect("first wall contact: t V/D = 0.625" in out, "contact time", out)

    @t
    def drop_bulk_width_leaves_out_stranded_particles():
        # a retracted blob (5 rows of 40) and two particles the rim left behind on the wall at
        # x = -/+30 dx: the width of all fluid reaches them, the bulk width is the blob's
        blob = np.vstack([np.column_stack([(np.arange(40) - 19.5) * dx, np.full(40, (0.6 + j) * dx)])
                          for j in range(5)])
        stranded = np.array([[-30 * dx, 0.6 * dx], [30 * dx, 0.6 * dx]])
        h5 = write_drop(os.path.join(d, "stranded.h5"), [(0.0, disk), (0.01, np.vstack([blob, stranded]))])
        rc, out, err, rows = measure(h5)
        r0, r1 = rows
        expect(rc == 0 and near(r0["bulk_width_m"], float(r0["width_m"])), f"intact disk {r0}", out + err)
        expect(near(r1["width_m"], 60 * dx) and near(r1["bulk_width_m"], 39 * dx)
               and near(r1["bulk_width_over_D"], 39 / 20) and r1["detached"] == "2",
               f"stranded frame {r1}")

    @t
    def drop_interior_summation_density_sees_compression():
        # the disk squeezed uniformly to 0.99 of its size about its centre, the densities in the
        # file unchanged (as in ISPH): sum m/rho sees nothing, the interior summation density
        # sees the area shrink by 0.99^2 (+2.03 %)
        c = np.array([0.0, 0.015])
        h5 = write_drop(os.path.join(d, "squeezed.h5"), [(0.0, disk), (0.002, c + 0.99 * (disk - c))])
        rc, out, err, rows = measure(h5)
        r0, r1 = rows
        expect(rc == 0 and float(r1["volume_rel_err_first"]) == 0.0, f"sum m/rho {r1}", out + err)
        # full support (3 dx) inside a disk of radius 10 dx: the particles more than about
        # 2.25 dx inside the outer row (the open region begins 0.75 dx beyond it), radius ~7.5 dx
        expect(0.4 * N < int(r0["n_interior"]) < 0.7 * N, f"interior particles {r0['n_interior']} of {N}")
        expect(float(r0["interior_density_rel_err"]) == 0.0, "first frame")
        e = float(r1["interior_density_rel_err"])
        expect(abs(e - (1 / 0.99 ** 2 - 1)) < 2e-3, f"interior density error {e}, expected 0.0203")
        expect("interior summation density vs the first frame" in out, "summary line", out)

    @t
    def drop_pictures_of_chosen_frames():
        h5 = write_drop(os.path.join(d, "pics.h5"), [(0.0, disk), (0.003, disk - [0.0, 0.003])])
        png = os.path.join(d, "pics_frames.png")
        rc, out, err, rows = measure(h5, "--pictures", "0,0.14")
        expect(rc == 0 and os.path.getsize(png) > 0 and png in out, f"exit {rc}", out + err)
        rc, out, err = tool("drop_measure.py", h5, "--no-png", "--pictures", "soon")
        expect(rc == 2 and "--pictures" in err and "numbers" in err, f"--pictures soon: exit {rc}", err)
        rc, out, err = tool("drop_measure.py", h5, "--no-png", "--pictures", "-1")
        expect(rc == 2 and ">= 0" in err, f"--pictures -1: exit {rc}", err)

    @t
    def drop_split_disk_two_clusters():
        half = disk[np.abs(K[:, 0]) > 1]            # columns -1, 0, 1 removed: gap 4 dx
        h5 = write_drop(os.path.join(d, "split.h5"), [(0.0, disk), (0.01, half)])
        rc, out, err, rows = measure(h5)
        r = rows[1]
        expect(r["clusters"] == "2" and r["fragments"] == "2" and r["detached"] == "0"
               and r["fractured"] == "1", f"split frame {r}", out + err)
        expect(near(r["largest_cluster_fraction"], 0.5), f"largest {r['largest_cluster_fraction']}")
        expect(rows[0]["clusters"] == "1", "intact frame")
        rc, out, err, _ = measure(h5, "--no-fracture")
        expect(rc == 1 and "2 fragments" in out and "RESULT: FAIL" in out, f"exit {rc}", out + err)
        rc, out, err, _ = measure(h5, "--expect-fracture")
        expect(rc == 0 and "RESULT: PASS" in out, f"exit {rc}", out + err)
        # a link longer than the gap joins the halves again
        rc, out, err, rows = measure(h5, "--link", "4.5", "--max-gap", "10")
        expect(rows[1]["clusters"] == "1", f"link 4.5: {rows[1]['clusters']} clusters")

    @t
    def drop_hole_void_gap():
        holed = disk[np.sum(K * K, axis=1) > 16]    # hole of radius 4 dx
        one = disk[np.any(K != 0, axis=1)]          # one missing particle
        h5 = write_drop(os.path.join(d, "hole.h5"), [(0.0, disk), (0.005, one), (0.01, holed)])
        rc, out, err, rows = measure(h5)
        r1, r2 = rows[1], rows[2]
        # the nearest particle to the centre is at sqrt(17) dx: empty circle 2 sqrt(17) dx
        expect(abs(float(r2["void_gap_over_dx"]) - 2 * math.sqrt(17)) < 0.3,
               f"void {r2['void_gap_over_dx']} != {2 * math.sqrt(17):.3f}", out)
        expect(r2["clusters"] == "1" and r2["fractured"] == "1", f"hole frame {r2}")
        expect(near(r2["max_nn_gap_over_dx"], 1.0), "a clean hole leaves the NN gap at 1")
        expect(abs(float(r1["void_gap_over_dx"]) - 2.0) < 0.1 and r1["fractured"] == "0",
               f"one missing particle: {r1}")
        # void fraction: 0 intact; the hole (49 particles removed, 49 dx^2) less a rim of
        # about 0.75 dx: ~ pi 3.4^2 dx^2 of the first frame's N dx^2
        vf = float(r2["void_fraction"])
        expect(float(rows[0]["void_fraction"]) == 0.0 and 30 / N < vf < 49 / N,
               f"void fraction {vf * N:.1f} dx^2 not in (30, 49)")
        rc, out, err, _ = measure(h5, "--no-fracture")
        expect(rc == 1 and "void gap" in out, f"exit {rc}", out + err)
        rc, out, err, _ = measure(h5, "--no-fracture", "--max-gap", "9")
        expect(rc == 0, f"--max-gap 9: exit {rc}", out + err)
        expect(float(r2["crack_fraction"]) == float(rows[0]["crack_fraction"]),
               "an enclosed hole is no crack")

    @t
    def drop_open_crack_crack_fraction():
        # a slot 3 columns wide from the top down to row -6: open to the outside, so no
        # cluster split and no enclosed void; the closing (radius 3 dx) fills about
        # 2.5 dx x 17 dx + the mouth ~ 47 dx^2, 15 % of the disk (the intact disk: 3 %)
        slot = disk[~((np.abs(K[:, 0]) <= 1) & (K[:, 1] >= -6))]
        h5 = write_drop(os.path.join(d, "slot.h5"), [(0.0, disk), (0.01, slot)])
        rc, out, err, rows = measure(h5, "--no-fracture")
        r0, r1 = rows
        c0, c1 = float(r0["crack_fraction"]), float(r1["crack_fraction"])
        expect(0.02 < c0 < 0.04 and r0["fractured"] == "0", f"intact disk: crack {c0}", out)
        expect(0.12 < c1 < 0.18 and r1["clusters"] == "1"
               and float(r1["void_gap_over_dx"]) <= 1.5 and r1["fractured"] == "1",
               f"slot: {r1}", out)
        expect(rc == 1 and "crack fraction" in out, f"--no-fracture: exit {rc}", out + err)
        rc, out, err, rows = measure(h5, "--no-fracture", "--max-crack", "0.2")
        expect(rc == 0, f"--max-crack 0.2: exit {rc}", out + err)
        rc, out, err, rows = measure(h5, "--crack-radius", "1")
        expect(float(rows[1]["crack_fraction"]) < 0.5 * c1,
               f"a 1 dx closing does not fill the 2.5 dx slot: {rows[1]['crack_fraction']}")

    @t
    def drop_detached_particles():
        singles = np.array([[0.040, 0.003], [0.045, 0.003], [0.052, 0.003]])   # NN 5, 5, 7 dx
        pair = np.array([[-0.040, 0.003], [-0.039, 0.003]])                    # a 2-particle drop
        h5 = write_drop(os.path.join(d, "detached.h5"),
                        [(0.0, disk), (0.01, np.vstack([disk, singles])),
                         (0.02, np.vstack([disk, singles, pair]))])
        rc, out, err, rows = measure(h5)
        r1, r2 = rows[1], rows[2]
        expect(r1["clusters"] == "1" and r1["detached"] == "3" and r1["fractured"] == "0",
               f"singles: {r1}", out + err)
        expect(near(r1["largest_cluster_fraction"], N / (N + 3)), "largest fraction")
        expect(near(r1["max_nn_gap_over_dx"], 7.0), f"NN gap {r1['max_nn_gap_over_dx']}")
        # the 2-particle drop is a cluster, but no fragment (< 1 % of the particles): a
        # droplet off the rim is no fracture; with --min-fragment 0 every cluster counts
        expect(r2["clusters"] == "2" and r2["fragments"] == "1" and r2["detached"] == "3"
               and r2["fractured"] == "0", f"the 2-particle drop is a cluster: {r2}")
        rc, out, err, rows = measure(h5, "--min-fragment", "0")
        expect(rows[2]["fragments"] == "2" and rows[2]["fractured"] == "1",
               f"--min-fragment 0: {rows[2]}", out + err)
        rc, out, err, _ = measure(h5, "--no-fracture", "--until", "0.75")
        expect(rc == 0, f"detached particles alone are no fracture: exit {rc}", out + err)
        rc, out, err, rows = measure(h5, "--min-cluster", "3", "--no-fracture")
        r2 = rows[2]
        expect(rc == 0 and r2["clusters"] == "1" and r2["detached"] == "5"
               and r2["fractured"] == "0", f"--min-cluster 3: exit {rc}, {r2}", out + err)
        rc, out, err, _ = measure(h5, "--no-fracture", "--until", "0.75", "--max-nn-gap", "3")
        expect(rc == 1 and "NN gap 7" in out, f"--max-nn-gap: exit {rc}", out + err)

    @t
    def drop_volume_error_and_until():
        split = disk[np.abs(K[:, 0]) > 1]
        h5 = write_drop(os.path.join(d, "volume.h5"),
                        [(0.0, disk), (0.01, disk, 1 / 1.02), (0.02, split)])
        rc, out, err, rows = measure(h5)
        expect(near(rows[1]["volume_rel_err_first"], 0.02, 1e-9),
               f"volume error {rows[1]['volume_rel_err_first']}", out)
        rc, out, err, _ = measure(h5, "--max-volume-error", "0.01", "--until", "0.5")
        expect(rc == 1 and re.search(r"max 2 % at t V/D = 0\.5 .*FAIL", out) is not None,
               f"exit {rc}", out + err)
        rc, out, err, rows = measure(h5, "--max-volume-error", "0.03", "--no-fracture",
                                     "--until", "0.75")
        expect(rc == 0 and len(rows) == 2, f"--until 0.75: exit {rc}, {len(rows)} rows",
               out + err)
        rc, out, err, _ = measure(h5, "--no-fracture")
        expect(rc == 1, f"the split at t V/D = 1 is checked without --until: exit {rc}", out)
        rc, out, err, _ = measure(h5, "--expect-fracture", "--until", "0.75")
        expect(rc == 1 and "no fractured frame" in out, f"exit {rc}", out + err)

    @t
    def drop_sphere_3d():
        ball, _ = drop_lattice(R=4, centre=(0.0, 0.006, 0.0), dim=3)
        h5 = write_drop(os.path.join(d, "ball.h5"), [(0.0, ball)],
                        scene=drop_scene("ball", dim=3), dim=3)
        # the staircase of a sphere of 8 dx fills 12 % under the crack closing
        rc, out, err, rows = measure(h5, "--max-crack", "0.2")
        r = rows[0]
        expect(rc == 0 and near(r["width_over_D"], 1.0) and near(r["height_m"], 0.010),
               f"3D: {r}", out + err)
        vol = len(ball) * dx ** 3
        expect(near(r["volume_m3"], vol)
               and near(r["volume_rel_err_disk"], vol / (math.pi * 0.008 ** 3 / 6) - 1, 1e-7),
               f"3D volume {r}")
        expect(r["clusters"] == "1" and r["fractured"] == "0", f"3D clusters {r}")
        # the cube centres of an intact lattice (sqrt(3)/2 dx from the particles) are no void
        expect(float(r["void_fraction"]) == 0.0 and float(r["void_gap_over_dx"]) < 1.9,
               f"3D void {r['void_gap_over_dx']}, fraction {r['void_fraction']}")

    @t
    def drop_compare_several_runs():
        a = write_drop(os.path.join(d, "run_a.h5"), [(0.0, disk), (0.01, disk - [0, 0.01])],
                       scene=drop_scene("drop_alpha"))
        b = write_drop(os.path.join(d, "run_b.h5"),
                       [(0.0, disk), (0.01, disk[np.abs(K[:, 0]) > 1])],
                       scene=drop_scene("drop_beta"))
        cd = os.path.join(d, "cmp")
        rc, out, err = tool("drop_measure.py", a, "--compare", b, "--out-dir", cd, "--no-fracture")
        expect(rc == 1 and "drop_alpha" in out and "drop_beta" in out, f"exit {rc}", out + err)
        for f_ in ("drop_alpha_drop.csv", "drop_beta_drop.csv", "compare_drop.png"):
            expect(os.path.getsize(os.path.join(cd, f_)) > 0, f"no {f_}")
        expect(len(read_csv_rows(os.path.join(cd, "drop_beta_drop.csv"))) == 2, "beta rows")
        # the same scene name twice: the directory name is appended, then _2
        os.makedirs(os.path.join(d, "eps0"), exist_ok=True)
        a2 = shutil.copy(a, os.path.join(d, "eps0", "run_a.h5"))
        rc, out, err = tool("drop_measure.py", a, a2, a, "--out-dir", cd, "--prefix", "same")
        for f_ in ("drop_alpha_drop_drop.csv", "drop_alpha_eps0_drop.csv",
                   "drop_alpha_drop_2_drop.csv", "same_drop.png"):
            expect(rc == 0 and os.path.exists(os.path.join(cd, f_)), f"exit {rc}, no {f_}",
                   out + err)

    @t
    def drop_errors():
        expect_unreadable_files_fail("drop_measure.py", d, {"dim": 2})
        box = write_drop(os.path.join(d, "box.h5"), [(0.0, disk)], scene=drop_scene(shape="box"))
        rc, out, err = tool("drop_measure.py", box)
        expect(rc == 1 and "no disk fluid block" in err, f"box: exit {rc}", out + err)
        nowall = write_drop(os.path.join(d, "nowall.h5"), [(0.0, disk)],
                            scene=drop_scene(wall=False))
        rc, out, err = tool("drop_measure.py", nowall, "--no-png")
        expect(rc == 1 and "--wall-y" in err, f"no wall: exit {rc}", out + err)
        rc, out, err = tool("drop_measure.py", nowall, "--no-png", "--wall-y", "0.005")
        expect(rc == 0, f"--wall-y: exit {rc}", out + err)
        rows = read_csv_rows(os.path.join(d, "drop_synth_drop.csv"))
        expect(near(rows[0]["height_m"], 0.02), f"--wall-y height {rows[0]['height_m']}")
        rc, out, err = tool("drop_measure.py")
        expect(rc == 2, f"no file: exit {rc}", out + err)
        rc, out, err = tool("drop_measure.py", box, "--no-fracture", "--expect-fracture")
        expect(rc == 2, f"exclusive checks: exit {rc}", out + err)

    return T


def write_tank(path, p_error=0.0, speed=0.0, body_force=True, flag=True):
    """A 20 x 20 tank of water (dx = 5 mm, H = 0.1 m) at t = 0 and 0.5 s with p = rho g (y_s - y)
    (y_s the top row's height, the flagged layer) times (1 + p_error) and one particle moving at
    speed [m/s]; walls: one row below."""
    dx, rho, g = 5e-3, 1000.0, 9.81
    xs = (np.arange(20) + 0.5) * dx
    X, Y = np.meshgrid(xs, xs)
    fl = np.column_stack([X.ravel(), Y.ravel()])
    wall = np.column_stack([xs, np.full(20, -0.5 * dx)])
    n, nw = len(fl), len(wall)
    ys = fl[:, 1].max()
    scene = ('name = "tank"\ndimension = 2\n[fluid]\ndensity = 1000.0\nviscosity = 1.0\n'
             '[[blocks]]\nkind = "fluid"\nmin = [0.0, 0.0]\nmax = [0.1, 0.1]\n'
             + ('[effects.body_force]\nacceleration = [0.0, -9.81]\n' if body_force else ''))
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "vesph-1"
        f.attrs["dim"] = np.int64(2)
        f.attrs["scene"] = scene
        f.attrs["dx"] = np.float64(dx)
        for i, t in enumerate((0.0, 0.5)):
            g_ = f.create_group(f"frames/{i:06d}")
            g_.attrs["time"] = np.float64(t)
            g_.attrs["step"] = np.int64(i)
            g_.create_dataset("position", data=np.vstack([fl, wall]))
            v = np.zeros((n + nw, 2))
            v[5, 1] = speed
            g_.create_dataset("velocity", data=v)
            g_.create_dataset("kind", data=np.concatenate([np.zeros(n, np.uint8), np.ones(nw, np.uint8)]))
            p = np.concatenate([rho * g * (ys - fl[:, 1]) * (1 + p_error), np.zeros(nw)])
            g_.create_dataset("pressure", data=p)
            if flag:
                g_.create_dataset("free_surface", data=np.concatenate([(fl[:, 1] == ys).astype(np.uint8), np.zeros(nw, np.uint8)]))
    return path


def make_hydrostatic_tests(tmp):
    d = os.path.join(tmp, "tank")
    os.makedirs(d, exist_ok=True)
    gH = math.sqrt(9.81 * 0.1)

    def exact():
        rc, out, err = tool("hydrostatic_check.py", write_tank(os.path.join(d, "exact.h5")))
        expect(rc == 0 and "RESULT: PASS" in out, f"exact hydrostatic tank: exit {rc}", out + err)

    def pressure_off():
        rc, out, err = tool("hydrostatic_check.py", write_tank(os.path.join(d, "p3.h5"), p_error=0.03))
        expect(rc == 1 and "RESULT: FAIL" in out, f"3 % pressure error: exit {rc}", out + err)
        rc, out, err = tool("hydrostatic_check.py", os.path.join(d, "p3.h5"), "--tolerance", "0.05")
        expect(rc == 0, f"3 % error within --tolerance 0.05: exit {rc}", out + err)

    def moving():
        path = write_tank(os.path.join(d, "moving.h5"), speed=2e-3 * gH)
        rc, out, err = tool("hydrostatic_check.py", path)
        expect(rc == 1 and "FAIL" in out, f"a particle at 2e-3 sqrt(gH): exit {rc}", out + err)
        rc, out, err = tool("hydrostatic_check.py", path, "--max-speed", "3e-3")
        expect(rc == 0, f"within --max-speed 3e-3: exit {rc}", out + err)

    def no_flag_uses_block_top():
        # without free_surface flags y_s is the block top, half a spacing above the top row:
        # p = rho g (y_top_row - y) is then low by rho g dx/2 = 0.025 rho g H
        rc, out, err = tool("hydrostatic_check.py", write_tank(os.path.join(d, "noflag.h5"), flag=False))
        expect(rc == 1 and "2.5" in out, f"no flags: expected a 2.5e-2 error, exit {rc}", out + err)

    def bad_input():
        rc, out, err = tool("hydrostatic_check.py", write_tank(os.path.join(d, "nog.h5"), body_force=False))
        expect(rc == 2 and "body_force" in err, f"no body force: exit {rc}", out + err)
        rc, out, err = tool("hydrostatic_check.py", os.path.join(d, "missing.h5"))
        expect(rc != 0 and "no such file" in err, f"missing file: exit {rc}", out + err)

    return [("hydrostatic_check: exact tank passes", exact),
            ("hydrostatic_check: a 3 % pressure error fails unless tolerated", pressure_off),
            ("hydrostatic_check: a moving particle fails unless tolerated", moving),
            ("hydrostatic_check: without flags the block top is the surface", no_flag_uses_block_top),
            ("hydrostatic_check: no body force, missing file", bad_input)]


# ------------------------------------------------------------ die swell
DS_W, DS_DX, DS_EXIT = 0.01, 0.0004, 0.2      # 25 rows across the die
DS_SCENE = 'name = "die_swell_synth"\ndimension = 2\n[particles]\nspacing = 0.0004\n'
DS_U, DS_VY = 0.05, 0.001                    # centreline velocity, uniform v_y [m/s]
DS_A, DS_B, DS_C = 2.0e4, 30.0, -5.0e3       # T_xx = a y, T_yy = b, T_xy = c (y - W/2) [Pa]


def ds_particles(front, rows_far, swell_len=0.01, lane=1.0):
    """A die-swell-like frame: (position, kind). Die walls (kind 1): 3 rows below y = 0 and
    above y = W for x in [0, 0.2]; a floor row (kind 1) at y = -0.02 beyond the exit; inflow
    buffer (kind 3) at x < 0; fluid: 25 rows in the die (x < 0.2) and, for 0.2 < x < front, an
    extrudate centred on W/2 whose row count grows linearly from 25 at the exit to rows_far
    at x >= 0.2 + swell_len."""
    dx = DS_DX
    xd = (np.arange(int(round(DS_EXIT / dx))) + 0.5) * dx
    yf = (np.arange(25) + 0.5) * dx
    parts = [(np.column_stack([np.repeat(xd, 25), np.tile(yf, len(xd))]), 0)]
    yw = np.concatenate([-(np.arange(3) + 0.5) * dx, DS_W + (np.arange(3) + 0.5) * dx])
    parts.append((np.column_stack([np.repeat(xd, 6), np.tile(yw, len(xd))]), 1))
    xb = -(np.arange(3) + 0.5) * dx
    parts.append((np.column_stack([np.repeat(xb, 25), np.tile(yf, 3)]), 3))
    xe = DS_EXIT + (np.arange(int(round(0.08 / dx))) + 0.5) * dx
    parts.append((np.column_stack([xe, np.full(len(xe), -0.02)]), 1))
    xe = xe[xe < front]
    for x in xe:
        n = int(round(25 + (rows_far - 25) * min(1.0, (x - DS_EXIT) / swell_len)))
        y = 0.5 * DS_W + (np.arange(n) - 0.5 * (n - 1)) * dx * lane
        parts.append((np.column_stack([np.full(n, x), y]), 0))
    pos = np.vstack([q for q, _ in parts])
    kind = np.concatenate([np.full(len(q), k, np.uint8) for q, k in parts])
    return pos, kind


def ds_frames(stress=True):
    """(time, front, rows_far) of the synthetic run: the extrudate reaches 0.215, 0.235 m,
    then 0.26 m (all stations); from t = 0.3 s the far width is 29, 31, 30, 29, 31, 30 rows."""
    spec = [(0.0, 0.2, 30), (0.1, 0.215, 30), (0.2, 0.235, 30)]
    spec += [(0.3 + 0.1 * i, 0.26, n) for i, n in enumerate((29, 31, 30, 29, 31, 30))]
    return spec


def write_die_swell(path, stress=True, spec=None, scene=DS_SCENE, dim=2, frames=True, lane=1.0,
                    extra=None):
    """extra: fluid positions added to every frame (stragglers off the extrudate)."""
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "vesph-1"
        f.attrs["dim"] = np.int64(dim)
        f.attrs["scene"] = scene
        f.attrs["dx"] = np.float64(DS_DX)
        if not frames:
            return path
        for i, (t, front, rows_far) in enumerate(spec or ds_frames()):
            pos, kind = ds_particles(front, rows_far, lane=lane)
            if extra is not None:
                pos = np.vstack([pos, extra])
                kind = np.concatenate([kind, np.zeros(len(extra), np.uint8)])
            n = len(kind)
            g = f.create_group(f"frames/{i:06d}")
            g.attrs["time"] = np.float64(t)
            g.attrs["step"] = np.int64(100 * i)
            y = pos[:, 1]
            vel = np.zeros((n, 2))
            fl = kind == 0
            vel[fl, 0] = 4 * DS_U * y[fl] * (DS_W - y[fl]) / DS_W ** 2
            vel[fl, 1] = DS_VY
            g.create_dataset("id", data=np.arange(n, dtype=np.uint64))
            g.create_dataset("kind", data=kind)
            g.create_dataset("position", data=pos)
            g.create_dataset("velocity", data=vel)
            g.create_dataset("density", data=np.full(n, 1000.0))
            g.create_dataset("mass", data=np.full(n, 1000.0 * DS_DX ** 2))
            g.create_dataset("pressure", data=np.zeros(n))
            if stress:
                T = np.zeros((n, 3))
                T[fl, 0] = DS_A * y[fl]
                T[fl, 1] = DS_C * (y[fl] - 0.5 * DS_W)
                T[fl, 2] = DS_B
                g.create_dataset("extra_stress", data=T)
    return path


def make_die_swell_tests(tmp):
    d = os.path.join(tmp, "die_swell")
    os.makedirs(d, exist_ok=True)
    tol = DS_DX / DS_W                       # 0.04
    ve = write_die_swell(os.path.join(d, "ve.h5"))
    newt = write_die_swell(os.path.join(d, "newt.h5"), stress=False)

    def measure(path, *args, prefix=None):
        prefix = prefix or os.path.splitext(os.path.basename(path))[0]
        rc, out, err = tool("die_swell_measure.py", path, "--out-dir", d, "--prefix", prefix,
                            *args)
        res = {}
        for suf in ("swell.csv", "profiles.csv"):
            fn = os.path.join(d, f"{prefix}_{suf}")
            res[suf] = read_csv_rows(fn) if rc in (0, 1) and os.path.exists(fn) else []
        fn = os.path.join(d, f"{prefix}_summary.json")
        if rc in (0, 1) and os.path.exists(fn):
            with open(fn) as fh:
                res["json"] = json.load(fh)
        return rc, out, err, res

    def swell_ratio_and_steady():
        rc, out, err, res = measure(ve)
        rows = res["swell.csv"]
        expect(rc == 0 and len(rows) == 9, f"exit {rc}, {len(rows)} rows", out + err)
        cols = list(rows[0].keys())
        expect(cols == ["time_s", "ratio_x0.21", "ratio_x0.23", "ratio_x0.25", "ratio_average",
                        "filled_x0.21", "filled_x0.23", "filled_x0.25", "filled_average"],
               f"columns {cols}")
        nan = lambda v: math.isnan(float(v))  # noqa: E731
        expect(all(nan(rows[0][c]) for c in cols[1:]), f"t = 0 should be all NaN: {rows[0]}")
        expect(abs(float(rows[1]["ratio_x0.21"]) - 1.2) <= tol and nan(rows[1]["ratio_x0.23"])
               and nan(rows[1]["ratio_average"]), f"t = 0.1: {rows[1]}")
        expect(abs(float(rows[2]["ratio_x0.23"]) - 1.2) <= tol and nan(rows[2]["ratio_x0.25"])
               and nan(rows[2]["ratio_average"]), f"t = 0.2: {rows[2]}")
        for r, n in zip(rows[3:], (29, 31, 30, 29, 31, 30)):
            for c in cols[1:]:   # compact lattice: the filled width is the envelope's
                expect(abs(float(r[c]) - n * DS_DX / DS_W) <= 1e-9, f"t = {r['time_s']} {c}: "
                       f"{r[c]} != {n * DS_DX / DS_W}")
        js = res["json"]
        a = js["average"]
        expect(js["frames_used"] == 3 and abs(js["time_window_s"][0] - 0.6) < 1e-12
               and abs(js["time_window_s"][1] - 0.8) < 1e-12, f"window {js}")
        expect(abs(a["mean"] - 1.2) < 1e-9 and abs(a["half_range"] - 0.04) < 1e-9
               and abs(a["std"] - 0.04 * math.sqrt(2 / 3)) < 1e-9, f"steady {a}")
        st = js["stations"]
        expect([s["frames_defined"] for s in st] == [8, 7, 6]
               and all(abs(s["mean"] - 1.2) < 1e-9 for s in st), f"stations {st}")
        expect("mean 1.2" in out, "steady mean not printed", out)
        f = js["filled"]
        expect(abs(f["mean"] - 1.2) < 1e-9 and abs(f["std"] - 0.04 * math.sqrt(2 / 3)) < 1e-9
               and all(abs(s["filled_mean"] - 1.2) < 1e-9 for s in st), f"filled {f} {st}")
        # --from: all six full frames; a wider slab sees the same width
        rc, out, err, res = measure(ve, "--from", "0.3", "--window", "3", "--no-png")
        a = res["json"]["average"]
        expect(rc == 0 and res["json"]["frames_used"] == 6 and abs(a["mean"] - 1.2) < 1e-9,
               f"--from 0.3: exit {rc}, {res.get('json')}", out + err)
        # --until: the window's upper end (the frame at 0.3 s alone: 29 rows, 29/25 = 1.16; the
        # default later half, 0.6-0.8 s, cut at 0.7 s: two frames)
        rc, out, err, res = measure(ve, "--from", "0.3", "--until", "0.35", "--no-png")
        js = res.get("json", {})
        expect(rc == 0 and js.get("frames_used") == 1 and abs(js["average"]["mean"] - 1.16) < 1e-9
               and js["time_window_s"] == [0.3, 0.3] and js["until_s"] == 0.35,
               f"--from 0.3 --until 0.35: exit {rc}, {js}", out + err)
        rc, out, err, res = measure(ve, "--until", "0.7", "--no-png")
        expect(rc == 0 and res["json"]["frames_used"] == 2
               and abs(res["json"]["time_window_s"][1] - 0.7) < 1e-12,
               f"--until 0.7: exit {rc}, {res.get('json')}", out + err)
        rc, out, err, res = measure(ve, "--until", "nan", "--no-png")
        expect(rc == 2 and "--until" in err, f"--until nan: exit {rc}", out + err)

    def voids_between_lanes():
        # The extrudate's rows two dx apart (lanes with voids between them): 15 rows span
        # 29 dx, envelope ratio 29/25 = 1.16, filled ratio 15/25 = 0.6.
        lanes = write_die_swell(os.path.join(d, "lanes.h5"), lane=2.0,
                                spec=[(0.0, 0.2, 15), (0.1, 0.26, 15), (0.2, 0.26, 15)])
        rc, out, err, res = measure(lanes, "--no-png")
        r = res["swell.csv"][-1]
        # (at 0.21 m one of the slab's four columns is in the swelling stretch: 16 rows)
        expect(rc == 0 and abs(float(r["ratio_average"]) - 1.16) < 1e-9
               and abs(float(r["filled_x0.23"]) - 0.6) < 1e-9
               and abs(float(r["filled_x0.25"]) - 0.6) < 1e-9
               and abs(float(r["filled_x0.21"]) - 61 / 100) < 1e-9,
               f"lanes: envelope {r.get('ratio_average')}, filled {r}", out + err)
        rc, out, err, res = measure(lanes, "--filled-window", "0", "--no-png")
        expect(rc == 2 and "--filled-window" in err, f"--filled-window 0: exit {rc}", out + err)

    def profiles_with_stress_and_pngs():
        rc, out, err, res = measure(ve, "--expect-min", "1.15", "--expect-max", "1.25")
        prof = res["profiles.csv"]
        expect(rc == 0 and "PASS" in out and len(prof) == 25, f"exit {rc}, {len(prof)} rows",
               out + err)
        expect(list(prof[0].keys()) == ["y_m", "speed_m_s", "Txx_Pa", "Tyy_Pa", "Txy_Pa",
                                        "N1_Pa"], f"columns {list(prof[0].keys())}")
        ys = [float(r["y_m"]) for r in prof]
        expect(ys == sorted(ys) and abs(ys[0] - 0.5 * DS_DX) < 1e-12, f"y {ys[:3]}")
        for r in prof:
            y = float(r["y_m"])
            vx = 4 * DS_U * y * (DS_W - y) / DS_W ** 2
            ref = {"speed_m_s": math.hypot(vx, DS_VY), "Txx_Pa": DS_A * y, "Tyy_Pa": DS_B,
                   "Txy_Pa": DS_C * (y - 0.5 * DS_W), "N1_Pa": DS_A * y - DS_B}
            for k, v in ref.items():
                expect(abs(float(r[k]) - v) <= 1e-9 * max(1.0, abs(v)), f"y = {y}: {k} {r[k]} "
                       f"!= {v}")
        for suf in ("swell", "profiles", "n1"):
            fn = os.path.join(d, f"ve_{suf}.png")
            expect(os.path.exists(fn) and os.path.getsize(fn) > 0, f"no {fn}")
        # --profile-time: the frame nearest 0.14 s is t = 0.1 s (no full extrudate: still fine)
        rc, out, err, res = measure(ve, "--profile-time", "0.14", "--no-png")
        expect(rc == 0 and res["json"]["profile"]["time_s"] == 0.1, f"--profile-time: exit "
               f"{rc} {res.get('json', {}).get('profile')}", out + err)

    def newtonian_velocity_only():
        rc, out, err, res = measure(newt)
        prof = res["profiles.csv"]
        expect(rc == 0 and list(prof[0].keys()) == ["y_m", "speed_m_s"],
               f"exit {rc}, columns {list(prof[0].keys()) if prof else None}", out + err)
        expect("no extra_stress" in out, "the missing stress is not reported", out)
        expect(os.path.getsize(os.path.join(d, "newt_n1.png")) > 0, "no particle picture")
        expect(abs(res["json"]["average"]["mean"] - 1.2) < 1e-9, "Newtonian steady mean")
        # default prefix = scene name, default out-dir = the file's directory
        rc, out, err = tool("die_swell_measure.py", newt, "--no-png")
        expect(rc == 0 and os.path.exists(os.path.join(d, "die_swell_synth_swell.csv"))
               and not os.path.exists(os.path.join(d, "die_swell_synth_swell.png")),
               f"default prefix: exit {rc}", out + err)

    def expect_checks_fail():
        rc, out, err, res = measure(ve, "--no-png", "--expect-min", "1.25")
        expect(rc == 1 and "FAIL" in out and "OUTSIDE" in out
               and res["json"]["checks"][0]["pass"] is False, f"--expect-min 1.25: exit {rc}",
               out + err)
        rc, out, err, _ = measure(ve, "--no-png", "--expect-max", "1.1")
        expect(rc == 1 and "FAIL" in out, f"--expect-max 1.1: exit {rc}", out + err)
        # no frame with a defined average (the extrudate never reaches 0.25 m)
        short = write_die_swell(os.path.join(d, "short.h5"), spec=ds_frames()[:3])
        rc, out, err, res = measure(short, "--no-png", "--expect-min", "1.0")
        expect(rc == 1 and "no frame with a defined average" in out
               and res["json"]["average"]["mean"] is None, f"short run: exit {rc}", out + err)

    def bad_input():
        expect_unreadable_files_fail("die_swell_measure.py", d, {"format": "other"},
                                     prefix="die_swell_measure: error:")
        nof = write_die_swell(os.path.join(d, "noframes.h5"), frames=False)
        rc, out, err = tool("die_swell_measure.py", nof)
        expect(rc == 1 and "no /frames" in err, f"no frames: exit {rc}", out + err)
        d3 = write_die_swell(os.path.join(d, "d3.h5"), dim=3, frames=False)
        rc, out, err = tool("die_swell_measure.py", d3)
        expect(rc == 1 and "2D" in err, f"3D: exit {rc}", out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--stations", "0.19", "0.23")
        expect(rc == 2 and "not beyond the die exit" in err, f"station in die: exit {rc}",
               out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--profile-x", "0.22")
        expect(rc == 2 and "not inside the die" in err, f"profile x outside: exit {rc}",
               out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--profile-x", "-0.05", "--no-png")
        expect(rc == 1 and "no fluid particle" in err, f"profile x without fluid: exit {rc}",
               out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--expect-min", "1.3", "--expect-max",
                            "1.2")
        expect(rc == 2, f"--expect-min > --expect-max: exit {rc}", out + err)
        rc, out, err = tool("die_swell_measure.py", ve, "--window", "0")
        expect(rc == 2 and "--window" in err, f"--window 0: exit {rc}", out + err)

    return [("die_swell_measure: swell ratio per station, NaN before arrival, steady stats",
             swell_ratio_and_steady),
            ("die_swell_measure: filled (void-free) width of separated lanes", voids_between_lanes),
            ("die_swell_measure: analytic stress/velocity profiles, PNGs, --profile-time",
             profiles_with_stress_and_pngs),
            ("die_swell_measure: Newtonian run without extra_stress, default prefix",
             newtonian_velocity_only),
            ("die_swell_measure: --expect-min/--expect-max failures", expect_checks_fail),
            ("die_swell_measure: bad input errors and exit codes", bad_input)]


def make_die_swell_study_tests(tmp):
    import tomllib
    import die_swell_study as dss

    d = os.path.join(tmp, "die_swell_study")
    os.makedirs(d, exist_ok=True)

    def scenes():
        with open(dss.BASE_CASE, "rb") as fh:
            base = tomllib.load(fh)
        for study in dss.STUDIES:
            for r in dss.study_runs(study):
                shifted = dss.scene_for(r, 10, 1.5)
                ps = shifted["effects"].get("particle_shifting")
                expect(ps == {"coefficient": 1.5, "speed": dss.g6(r.v / 1.5)}
                       and "particle_shifting" not in dss.scene_for(r, 10)["effects"]
                       and shifted["effects"]["free_surface"] == (dss.scene_for(r, 10)["effects"].get("free_surface")
                                                                   or {"threshold": 0.8}),
                       f"{study}/{r.label}: --shifting scene wrong: {ps}, {shifted['effects'].get('free_surface')}")
                for n in (10, 25):
                    s = dss.scene_for(r, n)
                    back = tomllib.loads(dss.toml_dumps(s))
                    expect(back == s, f"{study}/{r.label}: the TOML text does not read back")
                    if r.model == "oldroyd_b":   # the same mu and Psi1 = -2 alpha1 (RE contravariant)
                        ob = s["effects"]["oldroyd_b"]
                        expect("second_order_fluid" not in s["effects"]
                               and abs(s["fluid"]["viscosity"] + ob["polymer_viscosity"] - dss.MU) < 1e-4
                               and abs(2 * ob["polymer_viscosity"] * ob["relaxation_time"] + 2 * r.alpha1)
                               < 1e-5 * abs(r.alpha1), f"{r.label}: Oldroyd-B not matched: {ob}")
                    else:
                        expect(s["effects"]["second_order_fluid"]["alpha2"] == dss.g6(-0.1 * r.alpha1),
                               f"{r.label}: alpha2 != -0.1 alpha1")
                    expect(abs(s["inflow"]["mean_velocity"] - r.v / 1.5) < 1e-6 * r.v,
                           f"{r.label}: mean velocity != v/1.5")
                    e = s["effects"]
                    expect(("viscosity" in e) == (r.procedure == 3)
                           and ("stress_divergence" in e) == (r.procedure != 4),
                           f"{r.label}: procedure {r.procedure} has the wrong effects: {sorted(e)}")
                    isph = r.scheme == "isph"
                    expect(("equation_of_state" not in e and "continuity" not in e
                            and s.get("solver", {}).get("scheme") == "isph") if isph
                           else "solver" not in s and e["equation_of_state"]["sound_speed"] >= 120.0,
                           f"{r.label}: scheme {r.scheme} not set up")
                    if n == 25:    # the thesis resolution: the base case's geometry exactly
                        for k in range(3):
                            for key in ("min", "max"):
                                expect(np.allclose(s["blocks"][k][key], base["blocks"][k][key],
                                                   atol=1e-12),
                                       f"{r.label}: blocks[{k}].{key} {s['blocks'][k][key]} != "
                                       f"the base case's {base['blocks'][k][key]}")
                        for key in ("min", "max"):
                            expect(np.allclose(s["inflow"][key], base["inflow"][key], atol=1e-12),
                                   f"{r.label}: inflow.{key} differs from the base case")
        # --room: the default domain is the base case's (y from -0.01 to 0.02 m); room R puts
        # its lateral edges R die widths from the centreline, nothing else changes.
        r = dss.study_runs("frontier")[0]
        s0, s35 = dss.scene_for(r, 10), dss.scene_for(r, 10, room=3.5)
        expect(s0["domain"]["min"][1] == base["domain"]["min"][1]
               and s0["domain"]["max"][1] == base["domain"]["max"][1]
               and s35["domain"]["min"] == [s0["domain"]["min"][0], -0.03]
               and s35["domain"]["max"] == [s0["domain"]["max"][0], 0.04]
               and {k: v for k, v in s35.items() if k != "domain"}
               == {k: v for k, v in s0.items() if k != "domain"},
               f"--room: domain {s0['domain']} / {s35['domain']}")
        rc, out, err = tool("die_swell_study.py", "frontier", "--shifting", "1", "--room", "3.5",
                            "--dry-run", "--only", "re10_de1_leapfrog", "--out", d)
        expect(rc == 0 and os.path.exists(os.path.join(d, "frontier_shifting_room3.5", "re10_de1_leapfrog",
                                                       "re10_de1_leapfrog.toml")),
               f"--room 3.5 --dry-run: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "frontier", "--room", "1", "--dry-run", "--out", d)
        expect(rc == 2 and "--room" in err, f"--room 1: exit {rc}", err)
        # --wall-floor: pressure_floor on both die walls of a WCSPH run, nothing else changes;
        # an ISPH run (wsph_isph's) is left alone; --scheme isph refuses it.
        sf = dss.scene_for(r, 10, wall_floor=0.0)
        expect([b.get("pressure_floor") for b in sf["blocks"]] == [None, 0.0, 0.0]
               and {k: v for k, v in sf.items() if k != "blocks"} == {k: v for k, v in s0.items() if k != "blocks"}
               and [{k: v for k, v in b.items() if k != "pressure_floor"} for b in sf["blocks"]] == s0["blocks"],
               f"--wall-floor: blocks {sf['blocks']}")
        ri = [x for x in dss.study_runs("wsph_isph") if x.scheme == "isph"][0]
        expect(all("pressure_floor" not in b for b in dss.scene_for(ri, 10, wall_floor=0.0)["blocks"]),
               "--wall-floor: the ISPH run's walls were given a floor")
        rc, out, err = tool("die_swell_study.py", "contraction", "--wall-floor", "0", "--dry-run", "--out", d)
        expect(rc == 0 and os.path.exists(os.path.join(d, "contraction_floor0", "newtonian_a1_0", "newtonian_a1_0.toml")),
               f"--wall-floor 0 --dry-run: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "contraction", "--scheme", "isph", "--wall-floor", "0",
                            "--dry-run", "--out", d)
        expect(rc == 2 and "--wall-floor" in err, f"--wall-floor with --scheme isph: exit {rc}", err)
        # --surface-condition: [effects.surface_pressure] with the ISPH scene's flags (0.97) in a
        # WCSPH run, also over the shifting's 0.8; the ISPH run untouched; --scheme isph refuses.
        for shift in (0.0, 1.0):
            ss = dss.scene_for(r, 10, shifting=shift, surface=True)
            expect(ss["effects"].get("surface_pressure") == {}
                   and ss["effects"]["free_surface"]["threshold"] == 0.97,
                   f"--surface-condition (shifting {shift}): {ss['effects'].get('free_surface')}")
        si = dss.scene_for(ri, 10, surface=True)
        expect("surface_pressure" not in si["effects"] and si["effects"]["free_surface"] == {"threshold": 0.97},
               f"--surface-condition changed the ISPH run: {si['effects'].get('free_surface')}")
        rc, out, err = tool("die_swell_study.py", "contraction", "--wall-floor", "0", "--surface-condition",
                            "--dry-run", "--out", d)
        expect(rc == 0 and os.path.exists(os.path.join(d, "contraction_floor0_sp", "newtonian_a1_0", "newtonian_a1_0.toml")),
               f"--surface-condition --dry-run: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "contraction", "--scheme", "isph", "--surface-condition",
                            "--dry-run", "--out", d)
        expect(rc == 2 and "--surface-condition" in err, f"--surface-condition with --scheme isph: exit {rc}", err)
        de = {v: sorted(round(r.De, 9) for r in dss.study_runs("deborah") if r.v == v)
              for v in (5.0, 10.0)}
        expect(de == {5.0: [0, 0.02, 0.1, 0.2, 0.3], 10.0: [0, 0.02, 0.1, 0.2, 0.3, 0.4, 0.5]},
               f"Deborah numbers of Table 4-1: {de}")
        front = [r for r in dss.study_runs("frontier") if r.v == 10.0]
        expect(max(r.De for r in front) >= 1.0 and {r.integrator for r in front} == {"leapfrog", "arkode"},
               "the frontier study reaches De >= 1 at Re 10 under both integrators")
        rc, out, err = tool("die_swell_study.py", "procedures", "--dry-run", "--out", d)
        expect(rc == 0 and out.count(" run ") == 4
               and os.path.exists(os.path.join(d, "procedures", "case4", "case4.toml")),
               f"--dry-run: exit {rc}", out + err)
        # --scheme isph: every run of a study as ISPH, filed beside the WCSPH study; the ISPH
        # scene is the wsph_isph study's (predictor projection, density relaxation, symmetric
        # grad p in the right-hand side and the correction).
        rc, out, err = tool("die_swell_study.py", "frontier", "--scheme", "isph", "--dry-run",
                            "--only", "re10_de1_leapfrog", "--out", d)
        path = os.path.join(d, "frontier_isph", "re10_de1_leapfrog", "re10_de1_leapfrog.toml")
        expect(rc == 0 and out.count(" run ") == 1 and os.path.exists(path),
               f"--scheme isph --dry-run: exit {rc}", out + err)
        if os.path.exists(path):
            with open(path, "rb") as fh:
                s = tomllib.load(fh)
            expect(s["solver"] == {"scheme": "isph", "linear_solver": "umfpack",
                                   "gradient": "symmetric", "carried_pressure": "predictor",
                                   "density_relaxation_time": 3.2e-4}
                   and s["effects"]["pressure_gradient"]["form"] == "symmetric"
                   and "equation_of_state" not in s["effects"]
                   and s["integrator"]["type"] == "leapfrog",
                   f"--scheme isph scene: {s.get('solver')}, {sorted(s['effects'])}")
        rc, out, err = tool("die_swell_study.py", "wsph_isph", "--scheme", "isph", "--dry-run",
                            "--out", d)
        expect(rc == 2 and "already runs both" in err, f"--scheme isph wsph_isph: exit {rc}", err)

    def tabulation():
        # Two runs of the wsph_isph study with synthetic outputs: one finished (the synthetic
        # extrudate swells to 29, 31, 30 rows of 25 over the later half: mean 1.2, std 0.033,
        # one piece; three stragglers on the die's end face above the exit and one beyond the
        # front, all detached), one stopped as diverged.
        sd = os.path.join(d, "tab")
        face = [[DS_EXIT + 0.5 * DS_DX, DS_W + k * DS_DX] for k in (4, 6, 8)]
        stragglers = np.array(face + [[0.27, DS_W + 10 * DS_DX]])
        for label, status in (("wcsph", "ok"), ("isph", "diverged")):
            rd = os.path.join(sd, "wsph_isph", label)
            os.makedirs(rd, exist_ok=True)
            write_die_swell(os.path.join(rd, label + ".h5"), extra=stragglers if status == "ok" else None)
            js = {"status": status, "final_time": 0.8, "steps": 800,
                  "wall_seconds": 2.5, "message": "density deviation 0.6"}
            if status == "ok":
                js["flow"] = {"removed": 37, "released": 900}
            with open(os.path.join(rd, "summary.json"), "w") as fh:
                json.dump(js, fh)
        rc, out, err = tool("die_swell_study.py", "wsph_isph", "--measure-only", "--out", sd,
                            "--no-png")
        expect(rc == 0, f"--measure-only: exit {rc}", out + err)
        rows = {r["label"]: r for r in read_csv_rows(os.path.join(sd, "wsph_isph", "wsph_isph.csv"))}
        w, i = rows["wcsph"], rows["isph"]
        expect(abs(float(w["swell_mean"]) - 1.2) < 1e-9 and abs(float(w["swell_std"]) - 0.0326599) < 1e-6,
               f"swell mean/std {w['swell_mean']} {w['swell_std']}, expected 1.2, 0.03266", out)
        expect(w["clusters"] == "1" and w["detached"] == "4" and w["die_face_residue"] == "3"
               and w["stable"] == "True"
               and w["exit_status"] == "0" and w["thesis_swell"] == "1.362"
               and w["removed_at_outflow"] == "37" and i["removed_at_outflow"] == "nan",
               f"finished run: {w}", out)
        expect(i["exit_status"] == "3" and i["stable"] == "False" and "density" in i["message"],
               f"diverged run: {i}", out)
        expect(out.count("NO") >= 1 and "wcsph" in out, "the printed table", out)

    def bad_arguments():
        rc, out, err = tool("die_swell_study.py", "forms", "--only", "nosuch", "--dry-run",
                            "--out", d)
        expect(rc == 2 and "nosuch" in err, f"--only nosuch: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "forms", "--across", "3", "--dry-run")
        expect(rc == 2 and "--across" in err, f"--across 3: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "nosuch")
        expect(rc == 2, f"unknown study: exit {rc}", out + err)
        rc, out, err = tool("die_swell_study.py", "forms", "--vesph", "/nonexistent/vesph",
                            "--out", d)
        expect(rc == 2 and "no such executable" in err, f"missing vesph: exit {rc}", out + err)

    return [("die_swell_study: scenes of every study (TOML round trip, thesis geometry at 25 "
             "across, procedures' effects, ISPH, Table 4-1 De)", scenes),
            ("die_swell_study: --measure-only tabulation, stable and diverged runs", tabulation),
            ("die_swell_study: bad arguments", bad_arguments)]


def make_die_swell_lip_tests(tmp):
    d = os.path.join(tmp, "die_swell_lip")
    os.makedirs(d, exist_ok=True)

    def lip_table():
        # The synthetic die swell (25 rows in the die, 30 from 0.21 m on, T_yy = b = 30 Pa) with
        # a pressure falling linearly along the die at 1.5 times plane Poiseuille's gradient for
        # mu = 2 Pa s, U = 0.1 m/s (12 mu U / W^2 = 2.4e4 Pa/m) and p = 0 beyond the exit.
        scene = DS_SCENE + "[fluid]\ndensity = 1000.0\nviscosity = 2.0\n[inflow]\nmean_velocity = 0.1\n"
        h5 = write_die_swell(os.path.join(d, "lip.h5"), scene=scene)
        G = 1.5 * 12 * 2.0 * 0.1 / DS_W ** 2
        with h5py.File(h5, "r+") as f:
            for nm in f["frames"]:
                g = f["frames"][nm]
                x = g["position"][:, 0]
                g["pressure"][...] = np.where(x < DS_EXIT, G * (DS_EXIT - x), 0.0)
                # beyond the exit: the rows move along at 0.08 m/s and away from the centreline
                # at 0.05 m/s, and carry T_xx = -40 Pa
                y = g["position"][:, 1]
                beyond = x >= DS_EXIT
                g["velocity"][beyond, 0] = 0.08
                g["velocity"][beyond, 1] = np.sign(y[beyond] - 0.5 * DS_W) * 0.05
                g["extra_stress"][beyond, 0] = -40.0
        out_csv = os.path.join(d, "lip.csv")
        rc, out, err = tool("die_swell_lip.py", h5, "--frames", "4", "--csv", out_csv)
        expect(rc == 0 and "-3.6e+04 Pa/m" in out and "+50 %" in out,
               f"die gradient: exit {rc}", out + err)
        rows = read_csv_rows(out_csv) if os.path.exists(out_csv) else []
        expect(len(rows) == 13, f"{len(rows)} bands, expected 13 (exit - dx to exit + 2 W by 4 dx)")
        far = [r for r in rows if float(r["x0_m"]) >= 0.21]
        expect(far and all(abs(float(r["count_ratio"]) - 1.2) < 1e-6 for r in far),
               f"count ratio 30/25 beyond 0.21 m: {[r['count_ratio'] for r in far]}")
        expect(all(abs(float(r["T_yy_outer_Pa"]) - 30.0) < 1e-9 and abs(float(r["p_outer_Pa"])) < 1e-9
                   and abs(float(r["balance_outer_Pa"]) - 30.0) < 1e-9 for r in far),
               f"outer rows: p 0, T_yy 30, balance 30: {far[:1]}")
        expect(all(abs(float(r["v_outward_outer_m_s"]) - 0.05) < 1e-12
                   and abs(float(r["T_xx_outer_Pa"]) + 40.0) < 1e-9 for r in far),
               f"outer rows: outward velocity 0.05, T_xx -40: {far[:1]}")
        # momentum flux of 30 rows at u = 0.08 m/s, p = 0, T_xx = -40 Pa: J = 30 dx (rho u^2 + 40),
        # Q = 30 dx rho u; momentum width Q^2 / (rho J) / W = 1.2 rho u^2 / (rho u^2 + 40)
        j_exp = 30 * DS_DX * (1000.0 * 0.08 ** 2 + 40.0)
        w_exp = 1.2 * 6.4 / 46.4
        expect(all(abs(float(r["momentum_flux_N_m"]) - j_exp) < 1e-5 * j_exp     # the CSV's 6 digits
                   and abs(float(r["momentum_width"]) - w_exp) < 1e-5 * w_exp for r in far),
               f"momentum flux {j_exp:.6g} N/m, width {w_exp:.6g}: {[(r['momentum_flux_N_m'], r['momentum_width']) for r in far[:2]]}")
        expect(f"momentum flux {j_exp:.1f} N/m, momentum width {w_exp:.3f} W" in out,
               "the jet's momentum flux and width line", out)
        rc, out, err = tool("die_swell_lip.py", os.path.join(d, "missing.h5"))
        expect(rc == 1 and "die_swell_lip: error" in err, f"missing file: exit {rc}", out + err)
        rc, out, err = tool("die_swell_lip.py", h5, "--frames", "0")
        expect(rc == 2, f"--frames 0: exit {rc}", out + err)

    def lip_labels():
        # Runs of the same name in different study directories keep apart (the plot's curves
        # and the CSV are keyed by the label); the same file twice is numbered.
        sys.path.insert(0, HERE)
        import die_swell_lip as dsl
        got = dsl.run_labels(["out/a/s1/r/r.h5", "out/a/s2/r/r.h5", "out/b/q/q.h5"])
        expect(got == ["s1/r/r", "s2/r/r", "b/q/q"], f"labels {got}, expected one directory more for all")
        got = dsl.run_labels(["x/r/r.h5", "y/q/q.h5"])
        expect(got == ["r/r", "q/q"], f"labels {got}, expected the directory and name only")
        got = dsl.run_labels(["x/r/r.h5", "x/r/r.h5"])
        expect(len(set(got)) == 2 and got[1].endswith("#2"), f"the same file twice: {got}")

    return [("die_swell_lip: die pressure gradient against Poiseuille, bands past the exit", lip_table),
            ("die_swell_lip: run labels tell runs of the same name apart", lip_labels)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--keep", metavar="DIR", help="keep the synthetic outputs in DIR")
    ap.add_argument("--write", metavar="DIR", help="only write the synthetic cases to DIR")
    a = ap.parse_args()
    if a.write:
        write_channel_case(os.path.join(a.write, "channel2d"))
        write_3d_case(os.path.join(a.write, "box3d"))
        write_channel_case(os.path.join(a.write, "channel2d_int64ids"), uint64_type=("Int", 8))
        print(f"wrote synthetic cases under {a.write}")
        return 0
    tmp = a.keep or tempfile.mkdtemp(prefix="vesph_tools_test_")
    os.makedirs(tmp, exist_ok=True)
    r = Runner()
    try:
        for name, fn in (make_tests(tmp) + make_xpp_tests(tmp) + make_drop_tests(tmp)
                         + make_hydrostatic_tests(tmp) + make_die_swell_tests(tmp)
                         + make_die_swell_study_tests(tmp) + make_die_swell_lip_tests(tmp)):
            r.run(name, fn)
    finally:
        if not a.keep:
            shutil.rmtree(tmp, ignore_errors=True)
    print(f"{r.passed} passed, {r.failed} failed")
    return 0 if r.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
