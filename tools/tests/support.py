"""Shared fixtures of the post-processing tests (tools/tests/test_*.py): synthetic vesph-1
outputs written with h5py (nothing is committed), the runner of a tool's documented command
line, and the adapter that turns a group of checks into unittest test cases.

Run the tests from tools/ (so that the package vesph is importable):
    cd tools && /usr/bin/python3 -m unittest discover -s tests -v
The drop tests read the kernels from the vesph binary (`vesph list --json`): the environment
variable VESPH names it (default build/vesph). VESPH_TOOLS_TEST_KEEP=DIR keeps the synthetic
outputs in DIR.

    /usr/bin/python3 -m tests.support --write DIR    (from tools/) only writes the synthetic
                                                     Poiseuille and 3D cases to DIR

The synthetic outputs: a 2D plane-Poiseuille channel (the poiseuille_newtonian scene, SI
units: m, s, kg, Pa) whose fluid velocities are the exact analytic profile at t = 0, 0.0225,
0.045, 0.1125, 0.5 s, and a small 3D box with extra_stress [N,6] and free_surface, each written
as DIR/<name>.h5 + DIR/<name>.xdmf (XDMF 3 in the layout the C++ writer uses) + DIR/summary.json;
synthetic periodic start-up channels with known fields; XPP channels built from the 1-D
start-up; drop-impact lattices (disks, split disks, holes, slots, detached particles, a 3D
sphere); hydrostatic tanks; planar die-swell outputs (a 25-row die swelling to 29-31 rows).
What each module checks is in its docstring:
    test_analytic.py            vesph.analytic (Poiseuille start-up, XPP homogeneous shear)
    test_catalogue.py           vesph list --json: step limits and kernels (vesph.limits, .kernels)
    test_checks.py              poiseuille_check, xpp_steady_shear check
    test_output.py              vesph.output.Output; check_output; paraview_check (when installed)
    test_measure_channel.py     startup_channel_profiles
    test_measure_drop.py        drop_measure
    test_measure_hydrostatic.py hydrostatic_check
    test_measure_die_swell.py   die_swell_measure, die_swell_lip
    test_measure_dam_break.py   dam_break_front, Output.gauges()
    test_studies.py             die_swell_study
    test_imex_work_precision.py study_imex_work_precision (runs vesph: the --quick study)
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

TOOLS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.dont_write_bytecode = True      # no tools/__pycache__ left behind
PY = "/usr/bin/python3"

import h5py  # noqa: E402

from vesph.analytic import analytic_velocity  # noqa: E402

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


def read_text(path):
    """The text of a file (closed again)."""
    with open(path) as fh:
        return fh.read()


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


# ------------------------------------------------------------------- running
def tool(script, *args):
    """Run tools/SCRIPT (a tool's documented command line) with args: (exit status, stdout,
    stderr)."""
    p = subprocess.run([PY, os.path.join(TOOLS, script), *map(str, args)],
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
    from vesph.checks import xpp_shear as X
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


# ------------------------------------------------------------------- unittest adapter
class Checks(list):
    """A group's checks, (name, function) pairs; `t = checks.add` registers a function by its
    name (as a decorator)."""

    def add(self, fn):
        self.append((fn.__name__, fn))
        return fn


def suite(*makers):
    """A unittest suite of the checks that each make(tmp) returns as (name, function) pairs,
    tmp a fresh temporary directory (removed at exit unless VESPH_TOOLS_TEST_KEEP names a
    directory to write into instead). A check fails by raising AssertionError (expect)."""
    import atexit
    import unittest

    keep = os.environ.get("VESPH_TOOLS_TEST_KEEP")
    s = unittest.TestSuite()
    for make in makers:
        if keep:
            tmp = os.path.join(keep, make.__name__)
            os.makedirs(tmp, exist_ok=True)
        else:
            tmp = tempfile.mkdtemp(prefix="vesph_tools_test_")
            atexit.register(shutil.rmtree, tmp, True)
        for name, fn in make(tmp):
            s.addTest(unittest.FunctionTestCase(fn, description=name))
    return s


def load_tests_of(*makers):
    """A module's load_tests (the unittest protocol): its TestCase classes and the checks of
    each group maker."""
    def load_tests(loader, tests, pattern):
        tests.addTests(suite(*makers))
        return tests
    return load_tests


def main():
    ap = argparse.ArgumentParser(description="write the synthetic Poiseuille and 3D cases")
    ap.add_argument("--write", metavar="DIR", required=True, help="directory to write them to")
    a = ap.parse_args()
    write_channel_case(os.path.join(a.write, "channel2d"))
    write_3d_case(os.path.join(a.write, "box3d"))
    write_channel_case(os.path.join(a.write, "channel2d_int64ids"), uint64_type=("Int", 8))
    print(f"wrote synthetic cases under {a.write}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
