"""dam_break_front (vesph.measure.dam_break) and Output.gauges() on synthetic dam breaks: a
column a = 1 m wide whose front follows the Koshizuka & Oka points (Z = z/a at T = t sqrt(2g/a)),
with and without a /gauges/front series."""
import math
import os
import subprocess
import sys

import h5py
import numpy as np

from support import expect, load_tests_of
from vesph import tool_environment
from vesph.measure.dam_break import reference
from vesph.output import Output

DX, A, G = 0.04, 1.0, 9.81
SCENE = ('name = "dam_break_synth"\ndimension = 2\n[fluid]\ndensity = 1000.0\n'
         '[[blocks]]\nkind = "fluid"\nmin = [0.0, 0.0]\nmax = [1.0, 2.0]\n'
         '[[blocks]]\nkind = "wall"\nmin = [-0.12, -0.12]\nmax = [4.12, 0.0]\n')
BODY_FORCE = '[effects.body_force]\nacceleration = [0.0, -9.81]\n'


def write_dam_break(path, shift=0.0, gauges=True, body_force=True):
    """Frames every 0.01 s to 0.3 s: a row of fluid particles whose last centre is at
    a Z_ko(T) - dx/2 + shift a (so the tool's Z is Z_ko + shift); with gauges, the front series
    and a point gauge in /gauges."""
    Tr, Zr = reference("ko")
    times = np.arange(31) * 0.01
    fronts = A * (np.interp(times * math.sqrt(2 * G / A), Tr, Zr) + shift) - 0.5 * DX
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "vesph-1"
        f.attrs["dim"] = np.int64(2)
        f.attrs["scene"] = SCENE + (BODY_FORCE if body_force else "")
        f.attrs["dx"] = np.float64(DX)
        for i, (t, xf) in enumerate(zip(times, fronts)):
            g = f.create_group(f"frames/{i:06d}")
            g.attrs["time"] = np.float64(t)
            g.attrs["step"] = np.int64(10 * i)
            x = np.concatenate([np.linspace(0.5 * DX, xf, 20), [2.0]])
            pos = np.column_stack([x, np.full(len(x), 0.5 * DX)])
            g.create_dataset("position", data=pos)
            g.create_dataset("kind", data=np.concatenate([np.zeros(20, np.uint8), [1]]).astype(np.uint8))
        if gauges:
            fr = f.create_group("gauges/front")
            fr.attrs["type"] = "front"
            fr.create_dataset("time", data=times)
            fr.create_dataset("front", data=fronts)
            pt = f.create_group("gauges/wall_p")
            pt.attrs["type"] = "point"
            pt.attrs["position"] = np.array([3.98, 0.16])
            pt.create_dataset("time", data=times)
            pt.create_dataset("pressure", data=np.full(len(times), np.nan))
            pt.create_dataset("kernel_sum", data=np.zeros(len(times)))
    return path


def front_tool(*args):
    p = subprocess.run([sys.executable, "-m", "vesph.measure.dam_break", *map(str, args)],
                       capture_output=True, text=True, env=tool_environment())
    return p.returncode, p.stdout, p.stderr


def make_dam_break_tests(tmp):
    def exact_data_passes():
        rc, out, err = front_tool(write_dam_break(os.path.join(tmp, "exact.h5")))
        expect(rc == 0 and "RESULT: PASS" in out and "gauge 'front'" in out, f"exact front: exit {rc}", out + err)
        expect("max |Z - Z_ref| = 0.0000 a" in out, "the exact front differs from the data", out)
        expect("rows checked: 26" in out, "t = 0.05 to 0.3 s in steps of 0.01 s: 26 rows", out)

    def shifted_front_fails():
        path = write_dam_break(os.path.join(tmp, "ahead.h5"), shift=0.3)
        rc, out, err = front_tool(path)
        expect(rc == 1 and "RESULT: FAIL" in out and "0.3000 a" in out, f"front 0.3 a ahead: exit {rc}", out + err)
        rc, out, err = front_tool(path, "--tolerance", "0.35")
        expect(rc == 0, f"within --tolerance 0.35: exit {rc}", out + err)

    def frames_without_gauges():
        rc, out, err = front_tool(write_dam_break(os.path.join(tmp, "nogauge.h5"), gauges=False))
        expect(rc == 0 and "frames (largest fluid x)" in out, f"front from the frames: exit {rc}", out + err)

    def gauges_accessor():
        with Output(write_dam_break(os.path.join(tmp, "acc.h5"))) as o:
            g = o.gauges()
            expect(sorted(g) == ["front", "wall_p"], f"gauges {sorted(g)}")
            expect(g["front"].type == "front" and g["front"].position is None, "front gauge")
            expect(list(g["wall_p"].position) == [3.98, 0.16] and g["wall_p"].type == "point", "point gauge")
            expect(len(g["front"]["time"]) == len(o.frames) == 31, "one row per frame")
            expect(math.isnan(g["wall_p"]["pressure"][0]), "a dry point is NaN")
        with Output(write_dam_break(os.path.join(tmp, "none.h5"), gauges=False)) as o:
            expect(o.gauges() == {}, "a file without gauges has none")

    def bad_input():
        rc, out, err = front_tool(write_dam_break(os.path.join(tmp, "nog.h5"), body_force=False))
        expect(rc == 2 and "body_force" in err, f"no body force: exit {rc}", out + err)
        rc, out, err = front_tool(os.path.join(tmp, "exact.h5"), "--gauge", "nope")
        expect(rc == 2 and "no front gauge named 'nope'" in err, f"unknown gauge: exit {rc}", out + err)

    return [("dam_break_front: the published points pass exactly", exact_data_passes),
            ("dam_break_front: a front 0.3 a ahead fails unless tolerated", shifted_front_fails),
            ("dam_break_front: without gauges the frames give the front", frames_without_gauges),
            ("Output.gauges(): types, positions, columns; none in a file without", gauges_accessor),
            ("dam_break_front: no body force, unknown gauge", bad_input)]


load_tests = load_tests_of(make_dam_break_tests)
