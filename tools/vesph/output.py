"""Reading vesph-1 output files (docs/user-guide.md §4): the one reader of the tools.

open_h5 and read_header open a file and check that it is a vesph output with its stored
scene, so that every tool reports a bad file the same way; Output reads the header, the
frame list, the frames' datasets (each checked against the particle count and dimension) and
the diagnostics, also of a file a run is still writing (opened without HDF5 locking, a
half-written last frame skipped with a note). ToolError and run_reporting_errors give the
tools' 'PROG: error: message' convention.
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


def nonnegative_list(what):
    """An argparse type: comma-separated numbers >= 0 (`what` names them in the error)."""
    import argparse

    def parse(text):
        try:
            vals = [float(v) for v in text.split(",") if v.strip()]
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what} separated by commas, got {text!r}")
        if not vals or any(not (v >= 0) for v in vals):
            raise argparse.ArgumentTypeError(f"expected {what} >= 0, got {text!r}")
        return vals
    return parse


def run_reporting_errors(prog, run, args):
    """run(args), turning a ToolError into 'PROG: error: message' on stderr and its status."""
    import sys

    try:
        return run(args)
    except ToolError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return e.status


# Shape of each per-particle dataset of a frame (docs/user-guide.md §4), n particles in dim
# dimensions; the extra stress holds the symmetric tensor's independent components
# (2D: xx xy yy; 3D: xx xy xz yy yz zz).
def _expected_shape(name, n, dim):
    if name in ("position", "velocity"):
        return (n, dim)
    if name == "extra_stress":
        return (n, 3 if dim == 2 else 6)
    return (n,)


class Gauge:
    """One gauge's series (Output.gauges): type, position (m, or None) and columns."""

    def __init__(self, type_, position, columns):
        self.type = type_
        self.position = position
        self.columns = columns

    def __getitem__(self, column):
        return self.columns[column]


class Output:
    """One vesph-1 output file: its header (the resolved scene, dim, dx, h, kernel), its frame
    list (name, time) in time order, and the frames' datasets.

    live: the file may belong to a run still writing it; a file locked by the writer is then
    opened without locking (a note says so), and read_or_skip skips an unreadable last frame.
    partial_last_frame: a last frame without its time attribute (being written) is skipped
    with a note instead of being an error.
    A tool's subclass checks the scene in _check_scene, called after the header is read and
    before the frames are listed (a file of the wrong kind is named before its frames)."""

    def __init__(self, path, live=False, partial_last_frame=False):
        self.path = path
        self.notes = []
        self.f, note = open_h5(path, allow_unlocked=live)
        self.live = note is not None
        if note:
            self.notes.append(note)
        try:
            self.scene, self.dim, self.dx = read_header(self.f, path)
            self._check_scene()
            self._list_frames(partial_last_frame)
        except Exception:
            self.f.close()
            raise

    def _check_scene(self):
        """Raise ToolError when the scene is not one the tool measures (subclasses)."""

    def _list_frames(self, partial_last_frame):
        f, path = self.f, self.path
        if "frames" not in f or len(f["frames"]) == 0:
            raise ToolError(f"{path} is not a vesph output with frames: no /frames groups")
        frames = []
        names = sorted(f["frames"].keys())
        for k, nm in enumerate(names):
            g = f["frames"][nm]
            if "time" not in g.attrs:
                if partial_last_frame and k == len(names) - 1:
                    self.notes.append(f"frame {nm} has no time yet (being written): skipped")
                    continue
                raise ToolError(f"{path}: frame {nm} has no time attribute")
            frames.append((float(g.attrs["time"]), k, nm,
                           int(g.attrs["step"]) if "step" in g.attrs else -1))
        if not frames:
            raise ToolError(f"{path}: no complete frame")
        frames.sort()
        self.frames = [(nm, t) for t, _, nm, _ in frames]
        self.steps = [step for _, _, _, step in frames]
        self.times = np.array([t for t, _, _, _ in frames])

    @property
    def name(self):
        """The scene's name, else the file name without .h5."""
        return str(self.scene.get("name", os.path.splitext(os.path.basename(self.path))[0]))

    @property
    def kernel(self):
        """The kernel's name: root attribute 'kernel', else particles.kernel of the scene."""
        if "kernel" in self.f.attrs:
            return as_str(self.f.attrs["kernel"])
        return str(self.scene.get("particles", {}).get("kernel", "quintic"))

    @property
    def h(self):
        """The smoothing length, m: root attribute 'h', else particles.smoothing_ratio x dx."""
        try:
            if "h" in self.f.attrs:
                return float(self.f.attrs["h"])
            return float(self.scene.get("particles", {}).get("smoothing_ratio", 1.6)) * self.dx
        except (TypeError, ValueError):
            raise ToolError(f"{self.path}: the smoothing length h is not a number")

    def group(self, k):
        """The HDF5 group of frame k."""
        return self.f["frames"][self.frames[k][0]]

    def has(self, k, dataset):
        return dataset in self.group(k)

    def read(self, k, datasets, optional=()):
        """The datasets of frame k as a dict of arrays, each checked against the particle
        count of 'kind' (or of the first dataset) and the dimension; those in optional are
        read when the frame has them."""
        nm = self.frames[k][0]
        g = self.group(k)
        for ds in datasets:
            if ds not in g:
                raise ToolError(f"{self.path}: frame {nm} has no dataset {ds!r}")
        names = list(datasets) + [ds for ds in optional if ds in g and ds not in datasets]
        out = {ds: g[ds][...] for ds in names}
        n = len(out["kind"]) if "kind" in out else len(out[names[0]])
        for ds in names:
            want = _expected_shape(ds, n, self.dim)
            if out[ds].shape != want:
                raise ToolError(f"{self.path}: frame {nm}: {ds} has shape {out[ds].shape}, "
                                f"expected {want}")
        return out

    def read_or_skip(self, k, datasets, optional=()):
        """read(k, ...), or None for an unreadable last frame of a file still being written
        (a note says so)."""
        try:
            return self.read(k, datasets, optional)
        except (ToolError, OSError, KeyError, ValueError, RuntimeError) as e:
            if isinstance(e, ToolError) and not self.live:
                raise
            nm = self.frames[k][0]
            if self.live and k == len(self.frames) - 1 and k > 0:
                self.notes.append(f"frame {nm} could not be read ({e}; being written?): skipped")
                return None
            raise ToolError(f"{self.path}: frame {nm} cannot be read ({e}); if the run is "
                            "still writing, copy the file and measure the copy")

    def diagnostics(self, *columns):
        """The diagnostics columns (time series, one value per step) as arrays."""
        if "diagnostics" not in self.f:
            raise ToolError(f"{self.path}: no /diagnostics group")
        d = self.f["diagnostics"]
        for c in columns:
            if c not in d:
                raise ToolError(f"{self.path}: the diagnostics have no column {c!r}")
        return [d[c][...] for c in columns]

    def gauges(self):
        """The gauges' series (/gauges, written when the scene has [[gauges]]; an extension of
        vesph-1, docs/user-guide.md "Gauges"): a dict name -> Gauge with .type ("point",
        "elevation" or "front"), .position (array, m; None for a front) and .columns, a dict
        column -> 1-D array with "time" first (one row per frame). Empty for files without
        gauges."""
        import h5py

        if "gauges" not in self.f:
            return {}
        out = {}
        for name, g in self.f["gauges"].items():
            if not isinstance(g, h5py.Group) or "time" not in g:
                raise ToolError(f"{self.path}: /gauges/{name} is not a gauge group with a time column")
            cols = {"time": g["time"][...]}
            for c in g:
                if c != "time":
                    cols[c] = g[c][...]
            for c, v in cols.items():
                if v.ndim != 1 or len(v) != len(cols["time"]):
                    raise ToolError(f"{self.path}: /gauges/{name}/{c}: expected a 1-D dataset as long as its time")
            position = np.asarray(g.attrs["position"], dtype=float) if "position" in g.attrs else None
            out[name] = Gauge(as_str(g.attrs.get("type", "")), position, cols)
        return out

    def close(self):
        self.f.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
