"""Analytic (and semi-analytic) reference solutions of the validation cases (docs/theory.md,
docs/validation.md), in SI units:

* analytic_velocity: transient plane Poiseuille flow from rest (Newtonian, series solution);
* couette_startup: start-up of plane Couette flow, one wall set moving (Newtonian, series);
* circular_couette: steady circular Couette flow between two rotating cylinders (Newtonian);
* waters_king: Waters & King's start-up of Oldroyd-B channel flow (dimensionless);
* pipe_newtonian_startup, pipe_oldroyd_b_startup, pipe_steady_stresses, pipe_startup_radial:
  Hagen-Poiseuille start-up in a pipe (Newtonian; Oldroyd-B after Waters & King, the pipe case;
  the steady stresses; a method-of-lines solution of the radial equations to check them);
* coefficients, steady_stresses, startup_velocity: the second-order fluid in channel flow;
* Xpp, steady_shear, steady_shear_ode, channel_reference, startup_1d: the extended Pom-Pom
  (XPP) model in steady homogeneous shear and its channel flow.
"""
import functools
import math

import numpy as np
from scipy import integrate, interpolate, optimize, special


# ------------------------------------------------------------------ plane Poiseuille start-up
SERIES_RTOL = 1e-16   # the series is summed until its terms are below this times u_centre

def analytic_velocity(y, t, F, nu, H, y0=0.0):
    """Transient plane Poiseuille velocity [m/s].

    y   : position(s) across the channel [m] (scalar or array); the walls
          are at y0 and y0 + H.
    t   : time since the fluid started from rest [s] (scalar, >= 0).
    F   : body-force acceleration along the channel [m/s^2].
    nu  : kinematic viscosity [m^2/s].
    H   : channel height [m].
    y0  : position of the lower wall [m] (default 0).

    The Fourier series is summed until the magnitude bound of the next term,
    4 F H^2 / (nu pi^3 (2n+1)^3) exp(-(2n+1)^2 pi^2 nu t / H^2), falls below
    1e-16 times the steady centreline velocity F H^2 / (8 nu).  At t == 0
    the exact initial state (zero velocity) is returned.  Returns a float
    for scalar y, else an ndarray shaped like y.
    """
    if t < 0:
        raise ValueError("analytic_velocity: t must be >= 0")
    if nu <= 0 or H <= 0:
        raise ValueError("analytic_velocity: nu and H must be > 0")
    s = np.asarray(y, dtype=np.float64) - y0
    scalar = s.ndim == 0
    s = np.atleast_1d(s)
    if t == 0.0:
        out = np.zeros_like(s)
        return float(out[0]) if scalar else out
    steady = F / (2.0 * nu) * s * (H - s)
    u_centre = abs(F) * H * H / (8.0 * nu)
    amp0 = 4.0 * F * H * H / (nu * math.pi ** 3)
    decay = math.pi ** 2 * nu * t / (H * H)
    threshold = SERIES_RTOL * u_centre
    total = np.zeros_like(s)
    n0 = 0
    chunk = 64
    while True:
        m = 2.0 * np.arange(n0, n0 + chunk) + 1.0          # (2n+1)
        coef = amp0 / m ** 3 * np.exp(-(m ** 2) * decay)  # term amplitudes
        keep = np.abs(coef) >= threshold
        if u_centre == 0.0:
            keep[:] = False
        # amplitudes decrease monotonically in n: the first dropped term
        # ends the sum.
        nkeep = int(np.argmin(keep)) if not keep.all() else chunk
        if nkeep > 0:
            total += np.sin(np.outer(m[:nkeep], s) * (math.pi / H)).T @ coef[:nkeep]
        if nkeep < chunk:
            break
        n0 += chunk
        if n0 > 10_000_000:   # only reachable for absurdly small t
            break
    out = steady - total
    return float(out[0]) if scalar else out


# --------------------------------------------------------------- circular Couette (steady)
def circular_couette(r, R1, R2, omega1, omega2=0.0):
    """Steady azimuthal velocity [m/s] between an inner cylinder of radius R1 turning at omega1
    and an outer one of radius R2 turning at omega2 (Newtonian, incompressible; the solution of
    d/dr (1/r d(r v)/dr) = 0 with v(R1) = omega1 R1, v(R2) = omega2 R2):

        v(r) = A r + B / r,  A = (omega2 R2^2 - omega1 R1^2) / (R2^2 - R1^2),
                             B = (omega1 - omega2) R1^2 R2^2 / (R2^2 - R1^2).

    r [m] (scalar or array), 0 < R1 < R2 [m], omega [rad/s]. Float for scalar r, else an array.
    """
    if not 0 < R1 < R2:
        raise ValueError("circular_couette: 0 < R1 < R2")
    A = (omega2 * R2 * R2 - omega1 * R1 * R1) / (R2 * R2 - R1 * R1)
    B = (omega1 - omega2) * R1 * R1 * R2 * R2 / (R2 * R2 - R1 * R1)
    r = np.asarray(r, dtype=np.float64)
    out = A * r + B / r
    return float(out) if out.ndim == 0 else out


# --------------------------------------------------------------- plane Couette start-up
def couette_startup(s, t, U, nu, H, ramp_time=0.0):
    """Start-up of plane Couette flow [m/s]: fluid at rest between a wall at rest (s = 0) and a
    wall set moving along the channel at t = 0 (s = H), at speed U f(t):

        f = 1 (ramp_time = 0): the impulsive start,
        u(s, t) = U s/H + (2U/pi) sum_{n>=1} ((-1)^n / n) sin(n pi s/H) exp(-lambda_n t),
        lambda_n = n^2 pi^2 nu / H^2;

        f = (1 - cos(pi t/T))/2 up to T = ramp_time, 1 after (vesph's ramp): by Duhamel's
        principle u = int_0^t f'(r) u_impulsive(s, t - r) dr, in closed form per mode
        u(s, t) = U f(t) s/H + (2U/pi) sum_n ((-1)^n / n) sin(n pi s/H) I_n(t),
        I_n = (w/2) [e^{-lambda_n (t - tau)} (lambda_n sin(w tau) - w cos(w tau)) + w e^{-lambda_n t}]
              / (lambda_n^2 + w^2),   w = pi/T, tau = min(t, T).

    s: distance(s) from the wall at rest [m]; t >= 0 [s]; nu [m^2/s]; H [m]. The series is
    summed until its terms are below 1e-16 of U (the ramp's, which fall like 1/n^3, 1e-12; at
    least 64 terms), in blocks of 4096 terms; at t = 0 the initial state (0 for s < H) is
    returned. Float for scalar s, else an array shaped like s.
    """
    if t < 0 or nu <= 0 or H <= 0 or ramp_time < 0:
        raise ValueError("couette_startup: t >= 0, nu > 0, H > 0 and ramp_time >= 0")
    s = np.asarray(s, dtype=np.float64)
    scalar = s.ndim == 0
    s = np.atleast_1d(s)
    if t == 0.0:
        out = np.where(s >= H, U if ramp_time == 0 else 0.0, 0.0)
        return float(out[0]) if scalar else out
    decay = math.pi ** 2 * nu * t / (H * H)
    nmax = 64
    if ramp_time == 0:
        while math.exp(-nmax * nmax * decay) / nmax >= 1e-16 and nmax < 1_000_000:
            nmax *= 2
    else:  # I_n falls like w / lambda_n: terms ~ 2 w H^2 / (nu pi^3 n^3) of U; to 1e-12 of U
        while 2.0 * (math.pi / ramp_time) * H * H / (nu * math.pi ** 3 * nmax ** 3) >= 1e-12 and nmax < 1_000_000:
            nmax *= 2
    w = math.pi / ramp_time if ramp_time > 0 else 0.0
    tau = min(t, ramp_time)
    factor = 1.0 if ramp_time == 0 else 0.5 * (1.0 - math.cos(w * tau))
    out = U * factor * s / H
    chunk = 4096  # terms per block (memory: len(s) x chunk)
    for n0 in range(1, nmax + 1, chunk):
        n = np.arange(n0, min(n0 + chunk, nmax + 1), dtype=np.float64)
        lam = n * n * math.pi ** 2 * nu / (H * H)
        if ramp_time == 0:
            weight = np.exp(-lam * t)
        else:
            weight = 0.5 * w * (np.exp(-lam * (t - tau)) * (lam * math.sin(w * tau) - w * math.cos(w * tau))
                                + w * np.exp(-lam * t)) / (lam * lam + w * w)
        coef = (2.0 * U / math.pi) * (-1.0) ** n / n * weight
        out = out + np.sin(np.outer(s, n) * (math.pi / H)) @ coef
    return float(out[0]) if scalar else out


# ------------------------------------------------------- Oldroyd-B start-up (Waters & King)
def startup_mode(T, alpha, beta):
    """Time function A(T) of one mode of the Oldroyd-B start-up (Waters & King 1970), T = t/lambda:
    the solution of A'' + (1 + beta alpha) A' + alpha A = 0 with A(0) = 1, A'(0) = -alpha.
    alpha = lambda nu0 k^2 for the mode's wavenumber k (nu0 = (eta_s + eta_p)/rho), beta =
    eta_s/(eta_s + eta_p). With b = (1 + beta alpha)/2, d = b^2 - alpha:
        d > 0: A = e^{-bT} [cosh cT + (b - alpha)/c sinh cT],  c = sqrt(d)
        d < 0: A = e^{-bT} [cos cT + (b - alpha)/c sin cT],    c = sqrt(-d)
        d = 0: A = e^{-bT} [1 + (b - alpha) T]."""
    b = 0.5 * (1.0 + beta * alpha)
    d = b * b - alpha
    if d > 0:
        c = math.sqrt(d)
        g = (b - alpha) / c
        # overflow-safe form of e^{-bT}[cosh cT + g sinh cT]
        return 0.5 * (1 + g) * np.exp((c - b) * T) + 0.5 * (1 - g) * np.exp(-(b + c) * T)
    if d < 0:
        c = math.sqrt(-d)
        return np.exp(-b * T) * (np.cos(c * T) + (b - alpha) / c * np.sin(c * T))
    return np.exp(-b * T) * (1 + (b - alpha) * T)


def startup_mode_rate(T, alpha, beta):
    """dA/dT of startup_mode (the same branches)."""
    b = 0.5 * (1.0 + beta * alpha)
    d = b * b - alpha
    if d > 0:
        c = math.sqrt(d)
        g = (b - alpha) / c
        return 0.5 * (1 + g) * (c - b) * np.exp((c - b) * T) - 0.5 * (1 - g) * (b + c) * np.exp(-(b + c) * T)
    if d < 0:
        c = math.sqrt(-d)
        h = (b - alpha) / c
        return np.exp(-b * T) * ((h * c - b) * np.cos(c * T) - (b * h + c) * np.sin(c * T))
    return np.exp(-b * T) * ((b - alpha) - b * (1 + (b - alpha) * T))


def mode_amplitude(T, E, beta, N):
    """The channel's mode N (= (2k - 1) pi): startup_mode with alpha = E N^2/4."""
    return startup_mode(T, E * N * N / 4.0, beta)


def waters_king(Y, T, E, beta, kmax=400):
    """U/Ubar at positions Y (array) and dimensionless time T."""
    Y = np.asarray(Y, dtype=float)
    u = 1.5 * (1.0 - Y * Y)
    for k in range(1, kmax + 1):
        N = (2 * k - 1) * math.pi
        A = mode_amplitude(T, E, beta, N)
        term = 48.0 * (-1) ** k / N ** 3 * np.cos(N * Y / 2.0) * A
        u = u + term
        if abs(48.0 / N ** 3 * A) < 1e-14:
            break
    return u


# ----------------------------------------------------- Hagen-Poiseuille start-up in a pipe
PIPE_MODES = 4000   # Bessel modes summed: the velocity series' tail is below 1e-8 of u_c


@functools.lru_cache(maxsize=None)
def pipe_modes(n=PIPE_MODES):
    """(j, c): the first n zeros j_k of J0 and the coefficients c_k = 8/(j_k^3 J1(j_k)) of the
    Fourier-Bessel series 1 - x^2 = sum_k c_k J0(j_k x) on 0 <= x <= 1 (docs/validation.md §17: the
    steady Hagen-Poiseuille profile; from int_0^1 x (1 - x^2) J0(j x) dx = 4 J1(j)/j^3 and the
    norm int_0^1 x J0(j x)^2 dx = J1(j)^2/2). Read-only arrays."""
    j = special.jn_zeros(0, n)
    c = 8.0 / (j ** 3 * special.j1(j))
    j.setflags(write=False)
    c.setflags(write=False)
    return j, c


def _pipe_series(r, R, time_functions):
    """(1 - x^2) - sum_k c_k J0(j_k x) A_k, x = r/R, for the mode time functions A_k
    (an array over the PIPE_MODES modes), in blocks of 500 modes. The modes whose weights
    |c_k A_k| sum to less than 1e-15 from there on are left out: |J0| <= 1, so they change the
    result by less than that (the decayed modes of a late time cost nothing)."""
    x = np.asarray(r, dtype=np.float64) / R
    scalar = x.ndim == 0
    x = np.atleast_1d(x)
    j, c = pipe_modes()
    weights = c * np.asarray(time_functions, dtype=np.float64)
    tail = np.cumsum(np.abs(weights)[::-1])[::-1]  # tail[k] = sum of |weights| from mode k on
    below = tail < 1e-15
    used = int(np.argmax(below)) if below.any() else len(j)
    out = 1.0 - x * x
    for k0 in range(0, used, 500):
        sl = slice(k0, min(k0 + 500, used))
        out = out - special.j0(np.outer(x, j[sl])) @ weights[sl]
    return float(out[0]) if scalar else out


def pipe_newtonian_startup(r, t, g, nu, R):
    """Hagen-Poiseuille start-up of a Newtonian fluid [m/s]: at rest at t = 0 in a pipe of
    radius R with no slip at r = R, driven by the body acceleration g along the axis:
        u(r, t) = (g R^2/(4 nu)) [(1 - r^2/R^2) - sum_k c_k J0(j_k r/R) exp(-nu j_k^2 t/R^2)]
    (j_k the zeros of J0, c_k = 8/(j_k^3 J1(j_k)): pipe_modes; the sum cancels the steady
    profile at t = 0; its k-th term is 2 g R^2/(nu j_k^3 J1(j_k)) J0 e^{...}). r: radius(es) [m],
    t >= 0 [s], g [m/s^2], nu [m^2/s], R [m]. At t = 0 the exact initial state (0) is returned.
    Float for scalar r, else an array shaped like r."""
    if t < 0 or nu <= 0 or R <= 0:
        raise ValueError("pipe_newtonian_startup: t >= 0, nu > 0 and R > 0")
    if t == 0:
        return 0.0 if np.ndim(r) == 0 else np.zeros(np.shape(r))
    j, _ = pipe_modes()
    return g * R * R / (4.0 * nu) * _pipe_series(r, R, np.exp(-nu * j * j * t / (R * R)))


def pipe_oldroyd_b_startup(r, t, g, rho, eta_s, eta_p, lam, R):
    """Hagen-Poiseuille start-up of an Oldroyd-B fluid [m/s] (Waters & King 1970, the pipe):
    fluid and stress at rest at t = 0, no slip at r = R, body acceleration g along the axis.
    rho du/dt = rho g + (1/r) d(r T_rz)/dr, T_rz = eta_s du/dr + tau_rz and
    tau_rz + lam dtau_rz/dt = eta_p du/dr (the upper-convected terms vanish for tau_rz since
    tau_rr = 0); with u = u_s + sum_k a_k(t) J0(j_k r/R) and tau_rz likewise in J1, each mode obeys
        lam a'' + (1 + lam nu_s k^2) a' + nu0 k^2 a = 0,   k = j_k/R,
    a(0) = -u_c c_k (cancels the steady profile), a'(0) = nu0 k^2 u_c c_k (the initial
    acceleration is g: the stress starts at zero). In T = t/lam: startup_mode with
    alpha_k = lam nu0 j_k^2/R^2 and beta = eta_s/eta0; so
        u(r, t) = u_c [(1 - r^2/R^2) - sum_k c_k J0(j_k r/R) A_k(t/lam)],  u_c = g R^2/(4 nu0),
    eta0 = eta_s + eta_p, nu0 = eta0/rho, nu_s = eta_s/rho. eta_p = 0 (or lam = 0) is the
    Newtonian start-up. Float for scalar r, else an array shaped like r."""
    if t < 0 or rho <= 0 or R <= 0 or eta_s < 0 or eta_p < 0 or eta_s + eta_p <= 0 or lam < 0:
        raise ValueError("pipe_oldroyd_b_startup: t >= 0, rho > 0, R > 0, eta_s, eta_p, lam >= 0")
    eta0 = eta_s + eta_p
    if eta_p == 0 or lam == 0:
        return pipe_newtonian_startup(r, t, g, eta0 / rho, R)
    if t == 0:
        return 0.0 if np.ndim(r) == 0 else np.zeros(np.shape(r))
    j, _ = pipe_modes()
    nu0 = eta0 / rho
    alpha = lam * nu0 * j * j / (R * R)
    A = np.array([startup_mode(t / lam, a, eta_s / eta0) for a in alpha])
    return g * R * R / (4.0 * nu0) * _pipe_series(r, R, A)


def pipe_steady_stresses(r, g, rho, eta_s, eta_p, lam):
    """The steady Hagen-Poiseuille stresses of an Oldroyd-B fluid at radii r [m] (Pa), as a dict:
    du/dr = -g r/(2 nu0); the total shear stress T_rz = eta0 du/dr = -rho g r/2 (the force
    balance, whatever the fluid), split into the solvent part eta_s du/dr and the polymer part
    tau_rz = eta_p du/dr; the first normal-stress difference (polymer only)
    N1 = tau_zz - tau_rr = 2 lam eta_p (du/dr)^2 (tau_rr = 0). z: the axis, r: outwards."""
    r = np.asarray(r, dtype=np.float64)
    eta0 = eta_s + eta_p
    dudr = -g * rho * r / (2.0 * eta0)
    return {"dudr": dudr, "T_rz": eta0 * dudr, "solvent_rz": eta_s * dudr,
            "tau_rz": eta_p * dudr, "N1": 2.0 * lam * eta_p * dudr * dudr}


def pipe_startup_radial(g, rho, eta_s, eta_p, lam, R, times, n=200):
    """The same start-up solved directly (to check the series): the radial equations
        rho du/dt = rho g + (1/r) d(r (eta_s du/dr + tau_rz))/dr,
        dtau_rz/dt = (eta_p du/dr - tau_rz)/lam,
        dtau_zz/dt = 2 (du/dr) tau_rz - tau_zz/lam          (upper-convected; tau_rr = 0)
    by the method of lines: u at n cell centres r_i = (i + 1/2) R/n, the rate and the stresses
    at the cell faces (no flux through r = 0; no slip at r = R by the mirrored ghost value),
    LSODA (rtol 1e-9). lam = 0 or eta_p = 0: Newtonian (no stress equations; the stresses are
    returned as zero). Returns (r_cells, u[times, n], r_faces (1..n), tau_rz[times, n],
    tau_zz[times, n])."""
    dr = R / n
    rc = dr * (np.arange(n) + 0.5)
    rf = dr * np.arange(1, n + 1)        # faces 1..n (face n is the wall)
    viscoelastic = eta_p > 0 and lam > 0
    eta_solvent = eta_s if viscoelastic else eta_s + eta_p

    def rhs(t, z):
        u = z[:n]
        gdot = np.diff(np.concatenate([u, [-u[-1]]])) / dr       # at faces 1..n
        flux = rf * eta_solvent * gdot
        if viscoelastic:
            trz, tzz = z[n:2 * n], z[2 * n:]
            flux = flux + rf * trz
        du = g + np.diff(np.concatenate([[0.0], flux])) / (rho * rc * dr)
        if not viscoelastic:
            return du
        return np.concatenate([du, (eta_p * gdot - trz) / lam, 2.0 * gdot * trz - tzz / lam])

    times = np.asarray(times, dtype=float)
    size = 3 * n if viscoelastic else n
    scale_u = g * R * R / (4.0 * (eta_s + eta_p) / rho)
    sol = integrate.solve_ivp(rhs, (0.0, float(times[-1])), np.zeros(size), method="LSODA",
                              t_eval=times, rtol=1e-9, atol=1e-13 * max(scale_u, rho * abs(g) * R))
    if not sol.success:
        raise RuntimeError("pipe start-up (method of lines): " + sol.message)
    u = sol.y[:n].T
    if viscoelastic:
        return rc, u, rf, sol.y[n:2 * n].T, sol.y[2 * n:].T
    zero = np.zeros_like(u)
    return rc, u, rf, zero, zero


# ---------------------------------------------------- second-order fluid in a channel
NORMAL = {"contravariant": (-2.0, 0.0), "covariant": (0.0, 2.0), "mixed": (0.0, 0.0), "jaumann": (-1.0, 1.0)}


def coefficients(form, alpha1, alpha2):
    if form == "cef":
        return 0.5 * alpha1, -(0.5 * alpha1 + alpha2)
    return alpha1, alpha2


def steady_stresses(form, derivative, alpha1, alpha2, mu, g):
    """(T_xx, T_xy, T_yy) of steady simple shear at shear rate g (arrays)."""
    c1, c2 = coefficients(form, alpha1, alpha2)
    x, y = NORMAL[derivative]
    return (c2 + x * c1) * g * g, mu * g, (c2 + y * c1) * g * g


def startup_velocity(yy, t, F, nu, H, retardation, nmax=2001):
    """v at distances yy from the lower wall, time t; retardation = c1/rho (m^2)."""
    v = np.zeros_like(np.asarray(yy, dtype=float))
    for n in range(1, nmax + 1, 2):
        k = n * math.pi / H
        amp = 4 * F * H * H / (nu * n ** 3 * math.pi ** 3)
        rate = nu * k * k / (1 + retardation * k * k)
        v = v + amp * np.sin(k * yy) * (1 - math.exp(-rate * t))
        if amp < 1e-14 * F * H * H / nu:
            break
    return v


# ------------------------------------------------------------- XPP in homogeneous shear
class Xpp:
    """XPP parameters: G (Pa), lam_b (s), r (-), q (-), alpha (-), eta_s (Pa s)."""

    def __init__(self, G, lam_b, r, q, alpha, eta_s=0.0):
        self.G = float(G)
        self.lam_b = float(lam_b)
        self.r = float(r)
        self.q = float(q)
        self.nu = 2.0 / self.q
        self.alpha = float(alpha)
        self.eta_s = float(eta_s)

    @property
    def eta_p(self):
        return self.G * self.lam_b

    def F(self, tr, trsq):
        L2 = 1.0 + tr / (3.0 * self.G)
        if L2 <= 0:
            raise ValueError(f"tr(tau) = {tr} <= -3G: Lambda undefined")
        L = math.sqrt(L2)
        return (2.0 * self.r * math.exp(self.nu * (L - 1.0)) * (1.0 - 1.0 / L)
                + (1.0 - self.alpha * trsq / (3.0 * self.G ** 2)) / L2)

    def rate(self, kappa, tau):
        """dtau/dt for 3x3 kappa (kappa_ab = dv_a/dx_b) and tau (the ODE route)."""
        tt = tau @ tau
        Fv = self.F(np.trace(tau), np.trace(tt))
        relax = (self.alpha / self.G) * tt + Fv * tau + self.G * (Fv - 1.0) * np.eye(3)
        return kappa @ tau + tau @ kappa.T - relax / self.lam_b + self.G * (kappa + kappa.T)

    def describe(self):
        return (f"G = {self.G:g} Pa, lambda_0b = {self.lam_b:g} s, r = {self.r:g} "
                f"(lambda_0s = {self.lam_b / self.r:g} s), q = {self.q:g}, alpha = {self.alpha:g}, "
                f"eta_p = {self.eta_p:g} Pa s, eta_s = {self.eta_s:g} Pa s")


def shear_residual(x, gdot, p):
    """Steady simple shear, written out by components: x = (txx, txy, tyy, tzz)."""
    txx, txy, tyy, tzz = x
    tr = txx + tyy + tzz
    trsq = txx * txx + 2 * txy * txy + tyy * tyy + tzz * tzz
    Fv = p.F(tr, trsq)
    a, G, lb = p.alpha, p.G, p.lam_b
    return np.array([
        2 * gdot * txy - (a / G * (txx * txx + txy * txy) + Fv * txx + G * (Fv - 1)) / lb,
        gdot * tyy + G * gdot - (a / G * txy * (txx + tyy) + Fv * txy) / lb,
        -(a / G * (txy * txy + tyy * tyy) + Fv * tyy + G * (Fv - 1)) / lb,
        -(a / G * tzz * tzz + Fv * tzz + G * (Fv - 1)) / lb,
    ])


def _newton(gdot, p, guess):
    scale = np.array([p.G, p.G, p.G, p.G])
    fun = lambda z: shear_residual(z * scale, gdot, p) * p.lam_b / p.G
    z, info, ier, msg = optimize.fsolve(fun, guess / scale, xtol=1e-13, full_output=True)
    # fsolve may stop with "not making good progress" once at round-off: judge the residual
    if not np.max(np.abs(fun(z))) <= 1e-11 * max(1.0, np.max(np.abs(z))):
        raise RuntimeError(f"XPP steady shear: Newton did not converge at gdot = {gdot:g} 1/s: {msg}")
    return z * scale


def ucm_guess(gdot, p):
    wi = p.lam_b * gdot
    return np.array([2 * p.G * wi * wi, p.G * wi, 0.0, 0.0])


def steady_shear(gdot, p, steps=None):
    """(txx, txy, tyy, tzz) of steady shear at rate gdot, by Newton with continuation in gdot
    from Wi = lambda_0b gdot = 0.01 (where the UCM solution is within 1e-4 of XPP)."""
    if gdot == 0:
        return np.zeros(4)
    sign = 1.0 if gdot > 0 else -1.0
    g = abs(gdot)
    g0 = min(g, 0.01 / p.lam_b)
    x = _newton(g0, p, ucm_guess(g0, p))
    n = steps or max(2, int(math.ceil(8 * math.log10(g / g0 + 1))) + 2)
    for gg in np.geomspace(g0, g, n)[1:]:
        x = _newton(gg, p, x)
    return np.array([x[0], sign * x[1], x[2], x[3]])


def steady_shear_ode(gdot, p, t_end=None):
    """The same by integrating the homogeneous ODE from tau = 0 (LSODA, rtol 1e-11)."""
    kappa = np.zeros((3, 3))
    kappa[0, 1] = gdot
    idx = [(0, 0), (0, 1), (1, 1), (2, 2)]

    def f(t, y):
        tau = np.array([[y[0], y[1], 0], [y[1], y[2], 0], [0, 0, y[3]]])
        d = p.rate(kappa, tau)
        return [d[i, j] for i, j in idx]

    t_end = t_end or 60 * p.lam_b
    sol = integrate.solve_ivp(f, (0, t_end), np.zeros(4), method="LSODA", rtol=1e-11,
                              atol=1e-12 * p.G)
    if not sol.success:
        raise RuntimeError(sol.message)
    y = sol.y[:, -1]
    if np.max(np.abs(f(0, y))) * p.lam_b > 1e-8 * max(p.G, np.max(np.abs(y))):
        raise RuntimeError("the homogeneous ODE did not reach a steady state")
    return y


class FlowCurve:
    """Steady shear on a dense log grid of rates (continuation), interpolated; inverted for
    the rate at a given total shear stress T_xy = eta_s gdot + tau_xy."""

    def __init__(self, p, gdot_max, n=1500):
        self.p = p
        g0 = 1e-4 / p.lam_b
        g = np.geomspace(g0, gdot_max * 1.05, n)
        x = _newton(g[0], p, ucm_guess(g[0], p))
        rows = [x]
        for gg in g[1:]:
            x = _newton(gg, p, x)
            rows.append(x)
        tau = np.array(rows)
        self.g = np.concatenate([[0.0], g])
        self.tau = np.vstack([np.zeros(4), tau])
        self.T = p.eta_s * self.g + self.tau[:, 1]
        if np.any(np.diff(self.T) <= 0):
            k = int(np.argmax(np.diff(self.T) <= 0))
            raise RuntimeError(f"the flow curve T_xy(gdot) is not monotone near gdot = {self.g[k]:g} 1/s: "
                               "the stress-controlled reference is not unique")
        # interpolate in log(g) away from 0 and with the linear law below g0
        self._lg = np.log(g)
        self._splines = [interpolate.CubicSpline(self._lg, tau[:, k]) for k in range(4)]
        self._inv = interpolate.CubicSpline(np.log(self.T[1:]), self._lg)

    def tau_at_rate(self, gdot):
        gdot = np.asarray(gdot, dtype=float)
        a = np.abs(gdot)
        out = np.zeros(a.shape + (4,))
        lo = a < self.g[1]
        hi = ~lo
        if np.any(hi):
            lg = np.log(a[hi])
            for k in range(4):
                out[hi, k] = self._splines[k](lg)
        if np.any(lo):  # linear regime: tau_xy = eta_p gdot, normal stresses ~ gdot^2
            s = a[lo] / self.g[1]
            out[lo, 1] = self.tau[1, 1] * s
            for k in (0, 2, 3):
                out[lo, k] = self.tau[1, k] * s * s
        out[..., 1] *= np.sign(gdot)
        return out

    def rate_at_stress(self, T):
        T = np.asarray(T, dtype=float)
        a = np.abs(T)
        out = np.zeros(a.shape)
        hi = a >= self.T[1]
        if np.any(a > self.T[-1]):
            raise RuntimeError("shear stress beyond the tabulated flow curve")
        out[hi] = np.exp(self._inv(np.log(a[hi])))
        out[~hi] = a[~hi] / (self.p.eta_s + self.p.eta_p)
        return out * np.sign(T)


def channel_reference(y, p, rho, F, y0, y1, curve=None, n=4001):
    """Steady channel: T_xy, gdot, tau (4 components) and v_x at positions y."""
    yc = 0.5 * (y0 + y1)
    half = 0.5 * (y1 - y0)
    Tw = rho * abs(F) * half
    if curve is None:
        # the wall rate: solve eta_s g + tau_xy(g) = Tw by bracketing on Newton solutions
        gw = optimize.brentq(lambda g: p.eta_s * g + steady_shear(g, p)[1] - Tw,
                             1e-6 * Tw / (p.eta_s + p.eta_p), 10 * Tw / max(p.eta_s, 1e-3 * p.eta_p))
        curve = FlowCurve(p, gw)
    y = np.asarray(y, dtype=float)
    T = -rho * F * (y - yc)
    g = curve.rate_at_stress(T)
    tau = curve.tau_at_rate(g)
    # v(y) = int_{y0}^{y} gdot dy', on a fine grid (Simpson), symmetric about y_c
    s = np.linspace(y0, y1, n)
    gs = curve.rate_at_stress(-rho * F * (s - yc))
    vs = integrate.cumulative_trapezoid(gs, s, initial=0.0)
    # (cumulative trapezoid, second order: n = 4001 gives ~1e-7 relative; tools/test_tools.py
    # checks it against quadrature)
    v = np.interp(y, s, vs)
    return {"T_xy": T, "gdot": g, "tau": tau, "v": v, "curve": curve, "yc": yc, "half": half}


def startup_1d(p, rho, F, y0, y1, times, n=128):
    """Start-up from rest of the incompressible, fully developed channel flow, which is exactly
    one-dimensional: rho dv/dt = rho F + d(T_xy)/dy, T_xy = eta_s dv/dy + tau_xy, and tau obeys
    the homogeneous XPP equations at the local rate gdot = dv/dy (no convection: D/Dt = d/dt).
    Method of lines: v at n cell centres across [y0, y1], no slip by mirrored ghost values, the
    rate and tau at the n + 1 cell faces; LSODA (rtol 1e-8). Returns (y_cells, v[times, n],
    tau[times, 4, n + 1], y_faces)."""
    dy = (y1 - y0) / n
    a_, G, lb = p.alpha, p.G, p.lam_b

    def rhs(t, z):
        v = z[:n]
        txx, txy, tyy, tzz = z[n:].reshape(4, n + 1)
        g = np.diff(np.concatenate([[-v[0]], v, [-v[-1]]])) / dy
        tr = txx + tyy + tzz
        trsq = txx * txx + 2 * txy * txy + tyy * tyy + tzz * tzz
        L2 = 1.0 + tr / (3.0 * G)
        L = np.sqrt(L2)
        Fv = 2 * p.r * np.exp(p.nu * (L - 1)) * (1 - 1 / L) + (1 - a_ * trsq / (3 * G * G)) / L2
        d = np.concatenate([
            2 * g * txy - (a_ / G * (txx * txx + txy * txy) + Fv * txx + G * (Fv - 1)) / lb,
            g * tyy + G * g - (a_ / G * txy * (txx + tyy) + Fv * txy) / lb,
            -(a_ / G * (txy * txy + tyy * tyy) + Fv * tyy + G * (Fv - 1)) / lb,
            -(a_ / G * tzz * tzz + Fv * tzz + G * (Fv - 1)) / lb])
        dv = F + np.diff(p.eta_s * g + txy) / (dy * rho)
        return np.concatenate([dv, d])

    times = np.asarray(times, dtype=float)
    sol = integrate.solve_ivp(rhs, (0.0, float(times[-1])), np.zeros(n + 4 * (n + 1)), method="LSODA",
                              t_eval=times, rtol=1e-8, atol=1e-12 * max(p.G, rho * abs(F) * (y1 - y0)))
    if not sol.success:
        raise RuntimeError("1-D start-up: " + sol.message)
    yc = y0 + dy * (np.arange(n) + 0.5)
    yf = y0 + dy * np.arange(n + 1)
    return yc, sol.y[:n].T, sol.y[n:].T.reshape(len(times), 4, n + 1), yf
