"""Reading vesph-1 output files (docs/user-guide.md §4) for the Python tools: one place for
opening a file, checking that it is a vesph output and reading the stored scene, so that every
tool reports a bad file the same way.
"""
import os
import tomllib

import numpy as np


class ToolError(Exception):
    """An error reported as 'PROG: error: message' with an exit status."""

    def __init__(self, msg, status=1):
        super().__init__(msg)
        self.status = status


def as_str(value):
    """An HDF5 string attribute (bytes, numpy scalar or str) as str."""
    if isinstance(value, np.ndarray) and value.shape == ():
        value = value[()]
    if isinstance(value, (bytes, np.bytes_)):
        return bytes(value).decode("utf-8")
    return str(value)


def open_h5(path, allow_unlocked=False):
    """Open read-only. Returns (file, note). With allow_unlocked, a file locked by a running
    writer is opened without locking and note says so; otherwise note is None."""
    import h5py

    if not os.path.exists(path):
        raise ToolError(f"{path}: no such file")
    if os.path.isdir(path):
        raise ToolError(f"{path} is a directory; give the .h5 file of the run")
    try:
        return h5py.File(path, "r"), None
    except BlockingIOError:
        if not allow_unlocked:
            raise ToolError(f"{path} is locked by another process (a run still writing it?)")
    except OSError as e:
        if not allow_unlocked or "lock" not in str(e).lower():
            raise ToolError(f"{path} is not an HDF5 file ({e})")
    try:
        return h5py.File(path, "r", locking=False), (
            "the file is locked (a run is still writing it): opened without locking; "
            "the last frame may be incomplete")
    except (OSError, TypeError) as e:
        raise ToolError(f"{path} is locked by another process and cannot be opened without "
                        f"locking ({e}); copy it and measure the copy")


def read_header(f, path):
    """Check the root attributes of an open vesph output; return (scene dict, dim, dx)."""
    fmt = as_str(f.attrs["format"]) if "format" in f.attrs else None
    if fmt is None or not fmt.startswith("vesph-"):
        raise ToolError(f"{path} is not a vesph output: root attribute 'format' is "
                        + ("missing" if fmt is None else f"{fmt!r}, expected 'vesph-1'"))
    if "scene" not in f.attrs:
        raise ToolError(f"{path} is not a vesph output: root attribute 'scene' is missing")
    try:
        scene = tomllib.loads(as_str(f.attrs["scene"]))
    except tomllib.TOMLDecodeError as e:
        raise ToolError(f"{path}: the stored scene is not valid TOML ({e})")
    dim = int(f.attrs["dim"]) if "dim" in f.attrs else int(scene.get("dimension", 2))
    if dim not in (2, 3):
        raise ToolError(f"{path}: dim = {dim}, expected 2 or 3")
    if "dx" in f.attrs:
        dx = float(f.attrs["dx"])
    else:
        try:
            dx = float(scene["particles"]["spacing"])
        except (KeyError, TypeError, ValueError):
            raise ToolError(f"{path}: no particle spacing (root attribute dx or particles.spacing)")
    return scene, dim, dx


def run_reporting_errors(prog, run, args):
    """run(args), turning a ToolError into 'PROG: error: message' on stderr and its status."""
    import sys

    try:
        return run(args)
    except ToolError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return e.status
