"""vesph post-processing: reading vesph-1 outputs, analytic solutions, measurements, checks
and parameter studies (docs/user-guide.md, "Post-processing tools").

Modules
    output       the one reader of vesph-1 files (frames, fields, the scene, diagnostics,
                 files of a run in progress)
    catalogue    `vesph list --json`: what the vesph binary provides
    kernels      the SPH kernels, tabulated by the C++ (via the catalogue)
    limits       the explicit step limits with the C++ default coefficients
    analytic     Poiseuille start-up (channel and pipe), Waters & King (channel and pipe),
                 second-order fluid channel, XPP shear
    checks.*     validation checks against analytic solutions, the output format checker
    measure.*    drop impact, die swell, channel profiles, inflow, hydrostatic tank, dam-break front,
                 jet buckling,
                 plane sections of 3D runs
    studies.*    parameter studies that run vesph (work-precision, CFL, sound speed,
                 convergence, die swell, ISPH linear solvers, 3D performance)

Each tool runs as `/usr/bin/python3 -m vesph.<package>.<tool>` with tools/ on the Python path,
or through `tools/vesph-post <tool>` (which sets the path; `tools/vesph-post` lists the tools).
"""
import os

TOOLS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REPO = os.path.dirname(TOOLS)

# Tool name (the old script's name, without .py) -> module, for `vesph-post` and `python3 -m vesph`.
TOOL_MODULES = {
    "check_output": "vesph.checks.output_file",
    "same_run_check": "vesph.checks.same_run",
    "paraview_check": "vesph.checks.paraview",
    "poiseuille_check": "vesph.checks.poiseuille",
    "startup_channel_check": "vesph.checks.startup_channel",
    "second_order_channel_check": "vesph.checks.second_order_channel",
    "xpp_steady_shear": "vesph.checks.xpp_shear",
    "couette_check": "vesph.checks.couette",
    "pipe_check": "vesph.checks.pipe",
    "rotation_check": "vesph.checks.rotating_box",
    "circular_couette_check": "vesph.checks.circular_couette",
    "rod_climbing_check": "vesph.checks.rod_climbing",
    "hydrostatic_check": "vesph.measure.hydrostatic",
    "inflow_check": "vesph.measure.inflow",
    "drop_measure": "vesph.measure.drop",
    "dam_break_front": "vesph.measure.dam_break",
    "die_swell_measure": "vesph.measure.die_swell",
    "die_swell_lip": "vesph.measure.die_swell_lip",
    "startup_channel_profiles": "vesph.measure.channel_profiles",
    "section": "vesph.measure.section",
    "jet_buckling_measure": "vesph.measure.jet_buckling",
    "study_work_precision": "vesph.studies.work_precision",
    "study_cfl": "vesph.studies.cfl",
    "study_sound_speed": "vesph.studies.sound_speed",
    "study_convergence": "vesph.studies.convergence",
    "study_imex_work_precision": "vesph.studies.imex_work_precision",
    "die_swell_study": "vesph.studies.die_swell",
    "isph_bench": "vesph.studies.isph_bench",
    "bench_3d": "vesph.studies.bench_3d",
    "peer_dam_break": "vesph.studies.peer_dam_break",
}


def tool_command(module):
    """The command line prefix that runs a tool module in a child process
    ([python, -m, module]); run it with tool_environment()."""
    import sys

    return [sys.executable, "-m", module]


def tool_environment(base=None):
    """The environment (a copy of base, default os.environ) with tools/ first on PYTHONPATH,
    so that a child process can import this package."""
    env = dict(os.environ if base is None else base)
    env["PYTHONPATH"] = TOOLS + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env
