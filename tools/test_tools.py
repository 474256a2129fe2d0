#!/usr/bin/python3
"""Self-test for tools/poiseuille_check.py, tools/check_output.py and (when
ParaView is installed) tools/paraview_check.py.

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
        for name, fn in make_tests(tmp):
            r.run(name, fn)
    finally:
        if not a.keep:
            shutil.rmtree(tmp, ignore_errors=True)
    print(f"{r.passed} passed, {r.failed} failed")
    return 0 if r.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
