"""`vesph list --json` as the package reads it (vesph.catalogue, vesph.kernels, vesph.limits):
the default step-limit coefficients, the kernels' tables against their closed forms (thesis
eqs. 3.3, 3.4; Wendland C2), and that plain `vesph list` names the same things. Needs the
vesph binary (VESPH, default build/vesph)."""
import math
import subprocess
import unittest

import numpy as np

from vesph import catalogue, kernels, limits


# Closed forms of the kernel profiles and their 2D/3D normalisations, only to check the tables.
def cubic(q):
    return np.where(q < 1, 2 / 3 - q * q + 0.5 * q ** 3, np.where(q < 2, (2 - np.minimum(q, 2)) ** 3 / 6, 0))


def quintic(q):
    a, b, c = np.maximum(3 - q, 0), np.maximum(2 - q, 0), np.maximum(1 - q, 0)
    return a ** 5 - 6 * b ** 5 + 15 * c ** 5


def wendland_c2(q):
    return np.maximum(1 - 0.5 * q, 0) ** 4 * (2 * q + 1)


PROFILES = {"cubic": (cubic, 2.0, {2: 15 / (7 * math.pi), 3: 3 / (2 * math.pi)}),
            "quintic": (quintic, 3.0, {2: 7 / (478 * math.pi), 3: 1 / (120 * math.pi)}),
            "wendland_c2": (wendland_c2, 2.0, {2: 7 / (4 * math.pi), 3: 21 / (16 * math.pi)})}


class Catalogue(unittest.TestCase):
    def test_step_limit_coefficients(self):
        self.assertEqual(limits.default_coefficients("wcsph"),
                         {"cfl": 0.125, "viscous": 0.125, "force": 0.25, "relaxation": 0.5})
        self.assertEqual(limits.default_coefficients("isph")["cfl"], 0.175)
        for entry in catalogue.catalogue()["integrators"]:
            # the one-evaluation symplectic scheme has its own WCSPH default (performance.md)
            wcsph = 0.175 if entry["name"] == "symplectic" else 0.125
            self.assertEqual(entry["default_step_limits"]["cfl"], {"wcsph": wcsph, "isph": 0.175})

    def test_step_limits(self):
        h, c, nu = 4e-5, 0.1, 1e-6
        lim = limits.step_limits(h, c, nu, amax=2e-4)
        self.assertEqual(lim["acoustic"], 0.125 * h / c)
        self.assertEqual(lim["viscous"], 0.125 * h * h / nu)
        self.assertEqual(lim["force"], 0.25 * math.sqrt(h / 2e-4))
        self.assertEqual(lim["controls"], "acoustic")
        self.assertEqual(lim["smallest"], lim["acoustic"])
        self.assertEqual(limits.step_limits(h, c, nu, cfl=0.5)["acoustic"], 0.5 * h / c)
        self.assertEqual(limits.step_limits(h, c, nu, scheme="isph")["acoustic"], 0.175 * h / c)
        self.assertEqual(limits.step_limits(h, 0.0, 0.0)["smallest"], math.inf)

    def test_kernel_tables_match_the_closed_forms(self):
        q_rng = np.random.default_rng(3)
        for name, (f, support, sigma) in PROFILES.items():
            for dim in (2, 3):
                k = kernels.Kernel(name, dim)
                self.assertEqual(k.support, support)
                self.assertAlmostEqual(k.sigma, sigma[dim], delta=1e-15 * sigma[dim])
                q = np.concatenate([q_rng.uniform(0, support * 1.2, 2000), [0, 1, 2, support, 3.5]])
                exact = sigma[dim] * f(q)
                err = np.max(np.abs(k.W(q) - exact)) / (sigma[dim] * f(np.array(0.0)))
                self.assertLess(err, 1e-10, f"{name} {dim}D: W relative error {err:.2e}")
                # the derivative against a central difference of the closed form
                qi = q[(q > 1e-3) & (q < support - 1e-3) & (np.abs(q - 1) > 1e-3) & (np.abs(q - 2) > 1e-3)]
                dq = 1e-6
                fd = sigma[dim] * (f(qi + dq) - f(qi - dq)) / (2 * dq)
                derr = np.max(np.abs(k.dW_dq(qi) - fd)) / np.max(np.abs(fd))
                self.assertLess(derr, 1e-7, f"{name} {dim}D: dW/dq relative error {derr:.2e}")
                self.assertTrue(np.all(k.W(np.array([support, support * 1.5])) == 0.0))

    def test_unknown_kernel(self):
        with self.assertRaisesRegex(Exception, "unknown kernel 'gauss'"):
            kernels.Kernel("gauss", 2)

    def test_plain_list_names_the_same_entries(self):
        text = subprocess.run([catalogue.vesph_binary(), "list"], capture_output=True, text=True,
                              check=True).stdout
        data = catalogue.catalogue()
        for group in ("effects", "integrators", "kernels", "pressure_schemes", "linear_solvers",
                      "boundaries"):
            for entry in data[group]:
                self.assertIn(f"  {entry['name']:<20s} {entry['summary'].splitlines()[0]}", text)

    def test_missing_binary(self):
        with self.assertRaisesRegex(Exception, "cannot run /nonexistent/vesph list --json"):
            catalogue.catalogue("/nonexistent/vesph")


if __name__ == "__main__":
    unittest.main()
