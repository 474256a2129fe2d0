"""What the vesph binary knows, as `vesph list --json` prints it: effects, integrators with
their default step-limit coefficients, Butcher tables, kernels (tables of W(q) and dW/dq),
pressure schemes, linear solvers and boundaries. The Python tools read kernels and step
limits from here instead of copying the C++ (docs/architecture.md).

The binary: the argument, else the environment variable VESPH, else build/vesph of the
repository holding this package.
"""
import functools
import json
import os
import subprocess

from vesph import REPO
from vesph.output import ToolError

DEFAULT_VESPH = os.path.join(REPO, "build", "vesph")


def vesph_binary(vesph=None):
    """The vesph binary to ask: vesph, else $VESPH, else build/vesph of the repository."""
    return str(vesph or os.environ.get("VESPH") or DEFAULT_VESPH)


@functools.lru_cache(maxsize=None)
def _load(binary):
    try:
        proc = subprocess.run([binary, "list", "--json"], capture_output=True, text=True)
    except OSError as e:
        raise ToolError(f"cannot run {binary} list --json ({e}); build vesph or give its "
                        "path in the environment variable VESPH")
    if proc.returncode != 0:
        raise ToolError(f"{binary} list --json failed (exit {proc.returncode}): "
                        f"{proc.stderr.strip()[-300:]}")
    try:
        return json.loads(proc.stdout)
    except json.JSONDecodeError as e:
        raise ToolError(f"{binary} list --json did not print JSON ({e})")


def catalogue(vesph=None):
    """The parsed `vesph list --json` of the binary (run once per binary)."""
    return _load(vesph_binary(vesph))
