"""hydrostatic_check (vesph.measure.hydrostatic) on synthetic tanks."""
import math
import os


from support import (expect, load_tests_of, tool, write_tank)


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


# unittest collects the groups above through load_tests
load_tests = load_tests_of(make_hydrostatic_tests)
