"""The output format checker (check_output: good 2D/3D files, each broken HDF5/XDMF variant named)
and, when ParaView is installed, paraview_check on the synthetic XDMF."""
import json
import os
import re
import shutil
import subprocess
import tempfile
import unittest

import h5py
import numpy as np

from vesph.output import Output, ToolError, as_str

from support import (DX, F, H, NU, PY, SCENE_2D, Checks, analytic_velocity, expect, load_tests_of,
                     read_text, tool, write_3d_case, write_channel_case, write_h5)


def make_check_output_tests(tmp):
    T = Checks()
    t = T.add

    good = os.path.join(tmp, "good2d")
    write_channel_case(good)

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
            text = read_text(p)
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
    return T


def make_paraview_tests(tmp):
    T = Checks()
    t = T.add

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
            res = json.loads(read_text(x + ".json"))
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


class OutputReader(unittest.TestCase):
    """vesph.output.Output, the one reader of the tools, on small synthetic files."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="vesph_output_test_")
        self.addCleanup(shutil.rmtree, self.tmp, True)

    def write(self, name, frames, **kw):
        path = os.path.join(self.tmp, name)
        write_h5(path, SCENE_2D, 2, frames, **kw)
        return path

    @staticmethod
    def frame(t, step, n=3, **extra):
        fr = {"time": t, "step": step, "kind": np.zeros(n, np.uint8),
              "position": np.arange(2.0 * n).reshape(n, 2), "velocity": np.zeros((n, 2))}
        fr.update(extra)
        return fr

    def test_header_frames_in_time_order_and_datasets(self):
        path = self.write("a.h5", [self.frame(0.2, 20), self.frame(0.0, 0), self.frame(0.1, 10)])
        with Output(path) as out:
            self.assertEqual((out.dim, out.dx, out.name, out.kernel), (2, DX, "poiseuille_newtonian", "quintic"))
            self.assertEqual(out.h, 1.6 * DX)
            self.assertEqual([t for _, t in out.frames], [0.0, 0.1, 0.2])
            self.assertEqual([nm for nm, _ in out.frames], ["000001", "000002", "000000"])
            self.assertEqual(out.steps, [0, 10, 20])
            d = out.read(2, ("kind", "position"), optional=("velocity", "extra_stress"))
            self.assertEqual(sorted(d), ["kind", "position", "velocity"])
            self.assertEqual(d["position"].shape, (3, 2))
            (t,) = out.diagnostics("time")
            self.assertEqual(len(t), 12)
            with self.assertRaisesRegex(ToolError, "frame 000001 has no dataset 'density'"):
                out.read(0, ("kind", "density"))
            with self.assertRaisesRegex(ToolError, "no column 'released'"):
                out.diagnostics("released")

    def test_shape_mismatch_named(self):
        path = self.write("b.h5", [self.frame(0.0, 0, velocity=np.zeros((3, 3)))])
        with Output(path) as out:
            with self.assertRaisesRegex(ToolError, r"frame 000000: velocity has shape \(3, 3\), expected \(3, 2\)"):
                out.read(0, ("kind", "velocity"))

    def test_partial_last_frame(self):
        path = self.write("c.h5", [self.frame(0.0, 0), self.frame(0.1, 1)])
        with h5py.File(path, "r+") as f:
            del f["frames/000001"].attrs["time"]
        with self.assertRaisesRegex(ToolError, "frame 000001 has no time attribute"):
            Output(path)
        with Output(path, live=True, partial_last_frame=True) as out:
            self.assertEqual(len(out.frames), 1)
            self.assertIn("frame 000001 has no time yet (being written): skipped", out.notes)

    def test_not_a_vesph_file(self):
        plain = os.path.join(self.tmp, "plain.h5")
        with h5py.File(plain, "w") as f:
            f.attrs["format"] = "other"
        with self.assertRaisesRegex(ToolError, "not a vesph output"):
            Output(plain)
        with self.assertRaisesRegex(ToolError, "no such file"):
            Output(os.path.join(self.tmp, "missing.h5"))
        nofr = self.write("d.h5", [])
        with self.assertRaisesRegex(ToolError, "no /frames groups"):
            Output(nofr)

    def test_fixed_length_strings_and_as_str(self):
        path = self.write("e.h5", [self.frame(0.0, 0)], fixed_strings=True)
        with Output(path) as out:
            self.assertEqual(out.kernel, "quintic")
            self.assertEqual(out.scene["name"], "poiseuille_newtonian")
        self.assertEqual(as_str(np.bytes_(b"abc")), "abc")
        self.assertEqual(as_str(np.array(b"abc")), "abc")
        self.assertEqual(as_str("abc"), "abc")


# unittest collects the groups above through load_tests
load_tests = load_tests_of(make_check_output_tests, make_paraview_tests)
