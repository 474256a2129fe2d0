"""The SPH smoothing kernels as the C++ Kernel class computes them (include/vesph/core/kernel.hpp),
read from `vesph list --json`: per kernel its support (in h) and, per dimension, W(q) and dW/dq
at h = 1 sampled on a uniform grid with the profiles' knots on samples. W and dW/dq between
samples are cubic Hermite interpolants of the samples (relative error ~1e-12), so
W(r, h) = W(r/h) / h^D and dW/dr = dW/dq(r/h) / h^(D+1).
"""
import numpy as np

from vesph.catalogue import catalogue
from vesph.output import ToolError


class Kernel:
    """One kernel in one dimension, evaluated at q = r/h >= 0 (0 from the support on)."""

    def __init__(self, name, dim, vesph=None):
        entries = {k["name"]: k for k in catalogue(vesph)["kernels"]}
        if name not in entries:
            raise ToolError(f"unknown kernel {name!r} (expected one of {', '.join(entries)})")
        entry = entries[name]
        samples = entry["samples"][str(dim)]
        self.name, self.dim = name, dim
        self.support = float(entry["support"])
        self.sigma = float(samples["sigma"])
        self._w = np.asarray(samples["W"], dtype=float)
        self._dw = np.asarray(samples["dW_dq"], dtype=float)
        self._dq = self.support / (len(self._w) - 1)

    @classmethod
    def for_output(cls, out, vesph=None):
        """The kernel of a vesph.output.Output (its kernel name and dimension)."""
        try:
            return cls(out.kernel, out.dim, vesph)
        except ToolError as e:
            raise ToolError(f"{out.path}: {e}")

    def _hermite(self, q):
        """Interval index, position in it and the Hermite basis at q (clipped to the table)."""
        q = np.asarray(q, dtype=float)
        s = np.clip(q / self._dq, 0.0, len(self._w) - 1)
        i = np.minimum(s.astype(int), len(self._w) - 2)
        t = s - i
        return q, i, t

    def W(self, q):
        """W(q) at h = 1 (times 1/h^D for a smoothing length h); 0 for q >= support."""
        q, i, t = self._hermite(q)
        t2, t3 = t * t, t * t * t
        w = ((2 * t3 - 3 * t2 + 1) * self._w[i] + (t3 - 2 * t2 + t) * self._dq * self._dw[i]
             + (-2 * t3 + 3 * t2) * self._w[i + 1] + (t3 - t2) * self._dq * self._dw[i + 1])
        return np.where(q < self.support, w, 0.0)

    def dW_dq(self, q):
        """dW/dq at h = 1 (times 1/h^(D+1) for dW/dr); 0 for q >= support."""
        q, i, t = self._hermite(q)
        t2 = t * t
        dw = ((6 * t2 - 6 * t) * self._w[i] / self._dq + (3 * t2 - 4 * t + 1) * self._dw[i]
              + (-6 * t2 + 6 * t) * self._w[i + 1] / self._dq + (3 * t2 - 2 * t) * self._dw[i + 1])
        return np.where(q < self.support, dw, 0.0)
