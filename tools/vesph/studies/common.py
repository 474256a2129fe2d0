"""Shared helpers for the vesph parameter studies (vesph.studies).

Not a command: imported by
    vesph.studies.work_precision   accuracy against cost, per integrator  (tools/study_work_precision.py)
    vesph.studies.cfl              step-limit coefficients up to instability  (tools/study_cfl.py)
    vesph.studies.sound_speed      the density-variation parameter delta  (tools/study_sound_speed.py)
    vesph.studies.convergence      spatial and temporal orders  (tools/study_convergence.py)
    vesph.studies.imex_work_precision  arkode-imex on stiff cases  (tools/vesph-post study_imex_work_precision)

Every study runs the plane-Poiseuille start-up case (cases/poiseuille_newtonian.toml,
theory.md section 10) with `--set` overrides, one `vesph run` at a time, each in its own
temporary directory (removed afterwards unless --keep-runs), and reads summary.json and the
HDF5 frames (user-guide.md section 4).  SI units throughout (m, s, m/s).

What this module provides
-------------------------
* geometry(ny): the --set overrides for a channel of height H = 1e-3 m with ny particles
  across it (dx = H/ny), periodic length 20 dx, walls 5 dx thick (quintic kernel, h = 1.6 dx:
  the periodic length must be >= 3 x 1.1 x 3h = 15.84 dx, a wall >= 3h = 4.8 dx).
* sound_speed_rule(delta): the override for thesis eq. (3.38) with phi = 4,
  V = 2.5e-5 m/s, L = 1e-3 m.
* Runner: runs vesph (exit 0 -> "ok", exit 3 -> "unstable", anything else -> "failed",
  which makes the study exit non-zero), logs every command line to DIR/commands.txt.
* analytic_error(run, t): max over fluid particles |vx - v(y,t)| / (F H^2/(8 nu)) with
  v from vesph.analytic.analytic_velocity, F, nu, H from the resolved scene.
* temporal_error(run, ref, t): max over fluid particles, matched by id, of
  |vx - vx_ref| / (F H^2/(8 nu)).
* step_limits(...), step_control(run): the explicit stability limits of theory.md
  section 8 with vesph's default coefficients (vesph.limits, from `vesph list --json`), and
  how an adaptive run's steps relate to them (at the limit, held at a constant step just
  below it, or set by the error estimate); the step sizes are the
  differences of the diagnostics `time` column.
* write_csv, print_table, plot helpers.

Timings are wall_seconds from summary.json.  The runs use OMP_NUM_THREADS = --threads
(default 1), so that timings on a shared 2-core machine are less noisy than with two
threads competing with other work; they remain noisy.
"""

import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vesph import REPO as _REPO
from vesph import limits
from vesph.analytic import analytic_velocity
from vesph.checks.poiseuille import scene_parameters
from vesph.output import Output

REPO = Path(_REPO)
DEFAULT_VESPH = REPO / "build" / "vesph"   # the README's build (tools/run-tests.sh, tools/demo.sh)
DEFAULT_SCENE = REPO / "cases" / "poiseuille_newtonian.toml"

# The Poiseuille case (cases/poiseuille_newtonian.toml).
H = 1.0e-3          # channel height, m
NU = 1.0e-6         # kinematic viscosity, m^2/s
FORCE = 2.0e-4      # body-force acceleration, m/s^2
U_CENTRE = FORCE * H * H / (8.0 * NU)   # steady centreline velocity, 2.5e-5 m/s
SMOOTHING_RATIO = 1.6

FIXED_STEP_INTEGRATORS = ("leapfrog", "midpoint", "arkode-fixed")


# --------------------------------------------------------------------------- overrides

def fnum(x):
    """A float as TOML text that parses back to the same double."""
    return repr(float(x))


def vec(*xs):
    return "[" + ", ".join(fnum(x) for x in xs) + "]"


def geometry(ny, height=H, length_cells=20, wall_layers=5):
    """--set overrides for dx = height/ny, periodic length length_cells*dx, walls of
    wall_layers*dx, fluid 0..height (the layout of cases/poiseuille_newtonian.toml)."""
    dx = height / ny
    L = length_cells * dx
    w = wall_layers * dx
    return [f"particles.spacing={fnum(dx)}",
            f"domain.min={vec(0.0, -w)}",
            f"domain.max={vec(L, height + w)}",
            f"blocks[0].max={vec(L, height)}",
            f"blocks[1].min={vec(0.0, -w)}",
            f"blocks[1].max={vec(L, 0.0)}",
            f"blocks[2].min={vec(0.0, height)}",
            f"blocks[2].max={vec(L, height + w)}"]


def sound_speed_rule(delta, phi=4.0, velocity=2.5e-5, length=1.0e-3):
    return ("effects.equation_of_state.sound_speed="
            f"{{ phi = {fnum(phi)}, delta = {fnum(delta)}, velocity = {fnum(velocity)}, "
            f"length = {fnum(length)} }}")


def rule_sound_speed(delta, phi=4.0, velocity=2.5e-5, length=1.0e-3, nu=NU, g=FORCE):
    """c of thesis eq. (3.38), m/s (what vesph computes from sound_speed_rule)."""
    return math.sqrt(phi * max(velocity ** 2 / delta, nu * velocity / (length * delta),
                               g * length / delta))


def integrator_sets(kind, table=None, step=None, rtol=None):
    s = [f"integrator.type={kind}"]
    if table:
        s.append(f"integrator.table={table}")
    if step is not None:
        s.append(f"integrator.step={fnum(step)}")
    if rtol is not None:
        s.append(f"integrator.rtol={fnum(rtol)}")
    return s


def integrator_label(kind, table=None):
    if kind.startswith("arkode") and table:
        short = {"DORMAND_PRINCE_7_4_5": "DP5", "BOGACKI_SHAMPINE_4_2_3": "BS3",
                 "HEUN_EULER_2_1_2": "HE2", "ZONNEVELD_5_3_4": "Z4"}.get(table, table)
        return f"{kind} {short}"
    return kind


# --------------------------------------------------------------------------- limits

def step_limits(h, c, nu=NU, vmax=0.0, amax=FORCE, cfl=None, viscous=None, force=None, vesph=None):
    """The stability limits of theory.md section 8, s (vesph.limits.step_limits with this
    case's nu and body force); a coefficient not given is vesph's default."""
    return limits.step_limits(h, c, nu, vmax=vmax, amax=amax, cfl=cfl, viscous=viscous,
                              force=force, vesph=vesph)


# --------------------------------------------------------------------------- runs

@dataclass
class FluidFrame:
    time: float
    ids: np.ndarray      # sorted
    y: np.ndarray
    vx: np.ndarray
    rho: np.ndarray
    x: np.ndarray = None  # first coordinate (the scene sweep's extent of the fluid)
    vy: np.ndarray = None  # second velocity component (2D flows that are not along x)


@dataclass
class Run:
    label: str
    sets: list
    cmd: list
    returncode: int
    status: str                      # ok | unstable | failed
    message: str = ""
    summary: dict = field(default_factory=dict)
    scene: dict = field(default_factory=dict)
    dx: float = math.nan
    h: float = math.nan
    frames: list = field(default_factory=list)   # FluidFrame, in file order
    diag_time: np.ndarray = None
    diag_max_speed: np.ndarray = None
    directory: str = ""

    # convenient summary values
    def _s(self, key, default=math.nan):
        v = self.summary.get(key, default)
        return default if v is None else v

    @property
    def wall(self):
        return float(self._s("wall_seconds"))

    @property
    def steps(self):
        return int(self._s("steps", -1))

    @property
    def rhs_evals(self):
        return int(self._s("rhs_evals", -1))

    @property
    def rejected(self):
        return int(self._s("rejected_steps", -1))

    @property
    def final_time(self):
        return float(self._s("final_time"))

    @property
    def density_deviation(self):
        return float(self._s("max_density_deviation"))

    @property
    def sound_speed(self):
        return float(self._s("sound_speed"))

    @property
    def ok(self):
        return self.status == "ok"

    def frame_at(self, t, rtol=1e-6):
        """The frame whose time is within rtol of t, or None."""
        best = None
        for fr in self.frames:
            if abs(fr.time - t) <= rtol * max(abs(t), 1e-300):
                best = fr
        return best

    def step_sizes(self):
        """Accepted step sizes, s, from the diagnostics `time` column.  They equal the `dt`
        column of current builds; builds before commit ac193f7 wrote the previous step's
        size into the `dt` column of arkode runs, so the differences are used instead."""
        if self.diag_time is None or len(self.diag_time) == 0:
            return np.zeros(0)
        return np.diff(np.concatenate([[0.0], self.diag_time]))


def read_output(run, directory):
    """Fill run.summary, run.scene, run.frames and the diagnostics from directory."""
    sj = Path(directory) / "summary.json"
    if sj.exists():
        run.summary = json.loads(sj.read_text())
    h5name = run.summary.get("h5")
    h5path = Path(directory) / h5name if h5name else None
    if h5path is None or not h5path.exists():
        cands = sorted(Path(directory).glob("*.h5"))
        h5path = cands[0] if cands else None
    if h5path is None:
        return
    with Output(str(h5path)) as out:
        run.scene = out.scene
        run.dx = float(out.f.attrs["dx"])
        run.h = float(out.f.attrs["h"])
        for k, (_, t) in enumerate(out.frames):
            g = out.read(k, ("kind", "id", "position", "velocity", "density"))
            fl = g["kind"] == 0
            ids = g["id"][fl]
            order = np.argsort(ids, kind="stable")
            run.frames.append(FluidFrame(
                time=t, ids=ids[order], y=g["position"][fl, 1][order],
                vx=g["velocity"][fl, 0][order], rho=g["density"][fl][order],
                x=g["position"][fl, 0][order], vy=g["velocity"][fl, 1][order]))
        if "diagnostics" in out.f:
            run.diag_time, run.diag_max_speed = out.diagnostics("time", "max_speed")


class Runner:
    """Runs vesph for a study and keeps track of unexpected failures."""

    def __init__(self, args, study):
        self.vesph = str(args.vesph)
        self.scene = str(args.scene)
        self.threads = args.threads
        self.keep = args.keep_runs
        self.out = Path(args.out)
        self.out.mkdir(parents=True, exist_ok=True)
        self.study = study
        self.failures = []
        self.count = 0
        self.log = open(self.out / "commands.txt", "w")
        self.log.write(f"# {study}: every vesph command run, with OMP_NUM_THREADS={self.threads}\n")
        if not Path(self.vesph).exists():
            # the binary may be missing for a moment while it is rebuilt
            for _ in range(60):
                time.sleep(5)
                if Path(self.vesph).exists():
                    break
            else:
                sys.exit(f"{study}: vesph binary {self.vesph} not found (--vesph)")

    def run(self, label, sets, t_end, times=None, expect_frame=True):
        """Run vesph with the overrides `sets` to time.end = t_end, frames at `times`
        (default [t_end]).  Returns a Run; never raises for a failed run."""
        self.count += 1
        times = list(times) if times else [t_end]
        sets = list(sets) + [f"time.end={fnum(t_end)}",
                             "output.times=[" + ", ".join(fnum(t) for t in times) + "]"]
        tmp = tempfile.mkdtemp(prefix=f"vesph-{self.study}-")
        cmd = [self.vesph, "run", self.scene, "-o", tmp, "--quiet"]
        for s in sets:
            cmd += ["--set", s]
        self.log.write(" ".join(_shell_quote(c) for c in cmd) + "\n")
        self.log.flush()
        env = dict(os.environ, OMP_NUM_THREADS=str(self.threads))
        t0 = time.monotonic()
        for attempt in range(12):
            if Path(self.vesph).exists():
                break
            time.sleep(5)      # binary being rebuilt by someone else
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
            rc, err = proc.returncode, proc.stderr
        except OSError as e:
            rc, err = -1, str(e)
        elapsed = time.monotonic() - t0
        status = "ok" if rc == 0 else "unstable" if rc == 3 else "failed"
        run = Run(label=label, sets=sets, cmd=cmd, returncode=rc, status=status, directory=tmp)
        try:
            read_output(run, tmp)
        except Exception as e:  # a run that wrote unreadable output
            if status == "ok":
                status = run.status = "failed"
            err += f"\n(reading the output failed: {e})"
        lines = err.strip().splitlines()
        run.message = run.summary.get("message") or (lines[-1] if lines else "")
        if status == "ok" and expect_frame and run.frame_at(t_end) is None:
            run.status = status = "failed"
            run.message = f"no frame at t = {t_end}"
        if status == "failed":
            tail = "\n".join(err.strip().splitlines()[-5:])
            self.failures.append(f"{label}: exit {rc}: {tail or run.message}")
        if self.keep:
            dest = Path(self.keep) / f"{self.count:03d}"
            if dest.exists():
                shutil.rmtree(dest)
            shutil.move(tmp, dest)
            run.directory = str(dest)
        else:
            shutil.rmtree(tmp, ignore_errors=True)
        extra = "" if status == "ok" else f"  ({run.message[:110]})"
        print(f"[{self.count:3d}] {label:<58s} {status:<8s} {elapsed:7.1f} s{extra}",
              file=sys.stderr, flush=True)
        return run

    def finish(self):
        self.log.close()
        if self.failures:
            print(f"\n{self.study}: {len(self.failures)} run(s) failed unexpectedly:",
                  file=sys.stderr)
            for f in self.failures:
                print("  " + f, file=sys.stderr)
            return 1
        return 0


def _shell_quote(s):
    import shlex
    return shlex.quote(s)


# --------------------------------------------------------------------------- errors

def velocity_scale(run):
    rho, mu, F, y0, height = scene_parameters(run.scene)
    nu = mu / rho
    return F * height * height / (8.0 * nu), F, nu, y0, height


def analytic_error(run, t):
    """max over fluid particles |vx - v(y,t)| / (F H^2/(8 nu)) at the frame at t (NaN if the
    run has no such frame)."""
    fr = run.frame_at(t) if run.frames else None
    if fr is None:
        return math.nan
    U, F, nu, y0, height = velocity_scale(run)
    v = analytic_velocity(fr.y, fr.time, F, nu, height, y0)
    return float(np.max(np.abs(fr.vx - v))) / abs(U)


def temporal_error(run, ref, t):
    """max over fluid particles, matched by id, of |vx - vx_ref| / (F H^2/(8 nu))."""
    fr = run.frame_at(t) if run.frames else None
    fref = ref.frame_at(t) if ref is not None and ref.frames else None
    if fr is None or fref is None:
        return math.nan
    if fr.ids.shape != fref.ids.shape or not np.array_equal(fr.ids, fref.ids):
        raise ValueError(f"temporal_error: {run.label} and {ref.label} have different particles")
    U = velocity_scale(ref)[0]
    return float(np.max(np.abs(fr.vx - fref.vx))) / abs(U)


def density_deviation_at(run, t):
    fr = run.frame_at(t) if run.frames else None
    if fr is None:
        return math.nan
    rho0 = float(run.scene["fluid"]["density"])
    return float(np.max(np.abs(fr.rho - rho0))) / rho0


def step_control(run, cfl=None, viscous=None, rtol=1e-3, vesph=None, nu=None, scheme="wcsph",
                 elastic_speed=0.0, implicit_viscous=False, relaxation_time=None):
    """How the accepted steps of an (adaptive) run relate to the stability limit of each step,
    min(cfl h/(c + c_e + v_max), viscous h^2/nu, relaxation_coefficient lambda) (theory.md
    section 8; the force limit is not included).  Returns (at_limit, ratio, control):
      at_limit  fraction of steps within rtol of the limit,
      ratio     median of step / limit,
      control   "limit"  when at_limit >= 0.5 (the stability limit sets the step);
                "held"   when at least half of the steps have one and the same size, between
                         limit/1.5 and the limit: ARKODE keeps the step when the change its
                         controller proposes is a growth by less than 1.5 with its default
                         fixed-step bounds [1, 1.5], so the step stays just below the limit
                         although the error estimate would allow the limit.  vesph sets the
                         bounds to [1, 1] since commit ac193f7: "held" now flags a regression;
                "error"  otherwise (the error estimate sets the step).
    The first and the last step (start-up, landing on the end time) are not counted; a
    coefficient not given is vesph's default (vesph.limits) for the pressure scheme.
    nu: the kinematic viscosity of the viscous limit (default: the Poiseuille scene's).
    scheme "isph": no sound speed, the advective limit cfl h/v_max with the ISPH cfl.
    elastic_speed: c_e of a viscoelastic model in the acoustic limit; relaxation_time: lambda
    of a model whose relaxation is explicit (the relaxation limit).  implicit_viscous: the
    viscous term is integrated implicitly (arkode-imex), so the viscous limit does not apply
    and the limit is that of the explicit part (docs/theory.md section 9.5)."""
    dts = run.step_sizes()
    if len(dts) < 4 or not math.isfinite(run.h):
        return math.nan, math.nan, ""
    defaults = limits.default_coefficients(scheme, vesph=vesph)
    cfl = defaults["cfl"] if cfl is None else cfl
    viscous = defaults["viscous"] if viscous is None else viscous
    vprev = np.concatenate([[0.0], run.diag_max_speed[:-1]])
    if scheme == "isph":
        with np.errstate(divide="ignore"):
            acoustic = np.where(vprev > 0, cfl * run.h / np.maximum(vprev, 1e-300), np.inf)
    else:
        c = run.sound_speed if math.isfinite(run.sound_speed) else 0.0
        c += elastic_speed
        acoustic = cfl * run.h / (c + vprev) if c > 0 else np.full(len(dts), np.inf)
    lim = acoustic
    if not implicit_viscous:
        nu = velocity_scale(run)[2] if nu is None else nu
        if nu > 0:
            lim = np.minimum(lim, viscous * run.h ** 2 / nu)
    if relaxation_time:
        lim = np.minimum(lim, defaults["relaxation"] * relaxation_time)
    body, limb = dts[1:-1], lim[1:-1]
    at = float(np.mean(body >= (1.0 - rtol) * limb))
    ratio = float(np.median(body / limb))
    med = float(np.median(body))
    same = float(np.mean(np.abs(body - med) <= 1e-9 * med))
    if at >= 0.5:
        control = "limit"
    elif same >= 0.5 and 1.0 / 1.5 < ratio < 1.0:
        control = "held"
    else:
        control = "error"
    return at, ratio, control


def observed_order(e_coarse, e_fine, ratio=2.0):
    if not (e_coarse > 0 and e_fine > 0) or not (math.isfinite(e_coarse) and math.isfinite(e_fine)):
        return math.nan
    return math.log(e_coarse / e_fine) / math.log(ratio)


# --------------------------------------------------------------------------- output

def common_arguments(ap, study):
    ap.add_argument("--out", default=f"output/studies/{study}",
                    help=f"output directory for the CSV, the PNG and commands.txt "
                         f"(default output/studies/{study}, relative to the current directory)")
    ap.add_argument("--quick", action="store_true",
                    help="reduced study (about 1-2 minutes)")
    ap.add_argument("--vesph", default=str(DEFAULT_VESPH),
                    help=f"vesph binary (default {DEFAULT_VESPH.relative_to(REPO)} in the repository)")
    ap.add_argument("--scene", default=str(DEFAULT_SCENE),
                    help="base scene (default cases/poiseuille_newtonian.toml)")
    ap.add_argument("--threads", type=int, default=1,
                    help="OMP_NUM_THREADS for every run (default 1)")
    ap.add_argument("--keep-runs", metavar="DIR",
                    help="keep every run's output under DIR/NNN (default: delete)")


def fmt_value(v, spec):
    if v is None:
        return "-"
    if isinstance(v, float) and math.isnan(v):
        return "-"
    if spec == "s" or isinstance(v, str):
        return str(v)
    try:
        return format(v, spec)
    except (TypeError, ValueError):
        return str(v)


def print_table(rows, columns, file=sys.stdout):
    """columns: list of (key, header, format spec)."""
    cells = [[h for _, h, _ in columns]]
    for r in rows:
        cells.append([fmt_value(r.get(k), spec) for k, _, spec in columns])
    widths = [max(len(c[i]) for c in cells) for i in range(len(columns))]
    for n, c in enumerate(cells):
        print("  ".join(x.rjust(w) for x, w in zip(c, widths)), file=file)
        if n == 0:
            print("  ".join("-" * w for w in widths), file=file)


def markdown_table(rows, columns):
    """The same table as Markdown text (for docs/studies.md)."""
    lines = ["| " + " | ".join(h for _, h, _ in columns) + " |",
             "|" + "|".join("---" for _ in columns) + "|"]
    for r in rows:
        lines.append("| " + " | ".join(fmt_value(r.get(k), spec) for k, _, spec in columns) + " |")
    return "\n".join(lines)


def write_csv(path, rows, columns):
    keys = [k for k, _, _ in columns]
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(keys)
        for r in rows:
            out = []
            for k in keys:
                v = r.get(k)
                if v is None or (isinstance(v, float) and math.isnan(v)):
                    out.append("")
                elif isinstance(v, float):
                    out.append(f"{v:.6g}")
                else:
                    out.append(v)
            w.writerow(out)


def safe_plot(fn, path, *args):
    """Call fn(path, *args); a plot that cannot be drawn (e.g. every run failed, nothing
    positive to put on a log axis) is reported, not raised, so that the study still
    prints its table and its failures."""
    try:
        fn(path, *args)
    except Exception as e:  # noqa: BLE001
        print(f"warning: could not draw {path}: {type(e).__name__}: {e}", file=sys.stderr)


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.rcParams.update({"font.size": 8, "axes.titlesize": 9, "legend.fontsize": 7,
                         "lines.markersize": 4})
    return plt


def positive(values, floor=1e-17):
    """Values for a log axis: non-positive ones are raised to floor (shown at the bottom)."""
    a = np.asarray(values, dtype=float)
    return np.where(a > 0, a, floor)
