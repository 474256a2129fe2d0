"""Analytic solutions (vesph.analytic): Poiseuille start-up (t = 0, walls, steady and short-time
limits, the PDE), plane Couette start-up (walls, steady limit, the PDE, the ramp against Duhamel's
integral), steady circular Couette flow (wall speeds, the ODE) and the XPP homogeneous-shear solver (small-rate limit = Oldroyd-B, Newton
and ODE routes agree, flow-curve inversion, channel velocity, the 1-D start-up)."""

import numpy as np

from support import (F, H, NU, U_CENTRE, Checks, analytic_velocity, expect, load_tests_of)


def make_analytic_tests(tmp):
    T = Checks()
    t = T.add

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
    return T


def make_couette_tests(tmp):
    """Plane Couette start-up (moving walls): walls, steady limit, the PDE, the ramp against a
    numerical Duhamel integral of the impulsive series."""
    T = Checks()
    t = T.add
    from scipy.integrate import quad

    from vesph.analytic import couette_startup
    U = 1e-3

    @t
    def couette_walls_and_limits():
        for ramp in (0.0, 0.05):
            for tt in (1e-3, 0.03, 0.3):
                f = 1.0 if ramp == 0 or tt >= ramp else 0.5 * (1 - np.cos(np.pi * tt / ramp))
                w = couette_startup(np.array([0.0, H]), tt, U, NU, H, ramp)
                expect(abs(w[0]) < 1e-12 * U and abs(w[1] - f * U) < 1e-9 * U, f"walls {w} at t={tt}, ramp {ramp}")
            y = np.linspace(0, H, 11)
            steady = couette_startup(y, 20.0, U, NU, H, ramp)
            expect(np.max(np.abs(steady - U * y / H)) < 1e-12 * U, "steady limit")
        expect(isinstance(couette_startup(0.3e-3, 0.05, U, NU, H), float), "scalar gives a float")

    @t
    def couette_satisfies_pde():
        y = np.linspace(0.05e-3, 0.95e-3, 19)
        for ramp in (0.0, 0.05):
            for tt in (0.01, 0.03, 0.1):
                dt, dy = 1e-5, 2e-6
                u = lambda yy, s: couette_startup(yy, s, U, NU, H, ramp)
                dudt = (u(y, tt + dt) - u(y, tt - dt)) / (2 * dt)
                d2u = (u(y + dy, tt) - 2 * u(y, tt) + u(y - dy, tt)) / dy ** 2
                res = np.max(np.abs(dudt - NU * d2u)) / (U / 0.05)
                expect(res < 1e-4, f"PDE residual {res:.2e} at t={tt}, ramp {ramp}")

    @t
    def couette_ramp_is_duhamel():
        ramp = 0.05
        s = np.array([0.1e-3, 0.5e-3, 0.99e-3])
        fp = lambda r: 0.5 * np.pi / ramp * np.sin(np.pi * r / ramp) if r < ramp else 0.0
        for tt in (0.01, 0.05, 0.1):
            a = couette_startup(s, tt, U, NU, H, ramp)
            b = [quad(lambda r: fp(r) * couette_startup(si, tt - r, U, NU, H) if tt - r > 0 else 0.0,
                      0, min(tt, ramp), limit=200)[0] for si in s]
            expect(np.max(np.abs(a - np.array(b))) < 1e-7 * U, f"ramp {a} vs Duhamel {b} at t={tt}")
    return T


def make_xpp_solver_tests(tmp):
    T = Checks()
    t = T.add

    from vesph import analytic as X

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
    return T


def make_circular_couette_tests(tmp):
    """Steady circular Couette flow: the wall speeds, d/dr (1/r d(r v)/dr) = 0, solid-body
    rotation when both cylinders turn together."""
    T = Checks()
    t = T.add
    from vesph.analytic import circular_couette

    @t
    def circular_couette_walls_and_ode():
        R1, R2 = 0.5e-3, 1.0e-3
        for w1, w2 in ((4.0, 0.0), (0.0, -3.0), (2.0, 5.0)):
            ends = circular_couette(np.array([R1, R2]), R1, R2, w1, w2)
            expect(np.max(np.abs(ends - [w1 * R1, w2 * R2])) < 1e-15, f"wall speeds {ends} for {w1}, {w2}")
            r, h = np.linspace(0.6e-3, 0.9e-3, 7), 1e-6
            f = lambda x: (circular_couette(x + h, R1, R2, w1, w2) * (x + h)
                           - circular_couette(x - h, R1, R2, w1, w2) * (x - h)) / (2 * h) / x
            res = np.max(np.abs((f(r + h) - f(r - h)) / (2 * h))) / (max(abs(w1), abs(w2)) / R1)
            expect(res < 1e-6, f"ODE residual {res:.2e}")
        expect(abs(circular_couette(0.7e-3, R1, R2, 3.0, 3.0) - 3.0 * 0.7e-3) < 1e-18, "solid-body rotation")
        expect(isinstance(circular_couette(0.7e-3, R1, R2, 3.0), float), "scalar gives a float")
    return T


# unittest collects the groups above through load_tests
load_tests = load_tests_of(make_analytic_tests, make_couette_tests, make_circular_couette_tests,
                           make_xpp_solver_tests)
