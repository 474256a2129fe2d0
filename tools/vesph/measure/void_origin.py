"""Where the voids inside a free-surface flow come from: a pocket the flow closed over the
outside (a fold or a coil of a jet laying down on its pile encloses some of the surrounding air:
physical), or a void that opened inside the fluid (a rupture: the tensile instability, a
particle disorder; unphysical). Followed from frame to frame through the particles' ids.

The voids are those of `drop.grid_measures` on its grid `drop.open_grid`: the distance d to the
nearest fluid particle on a grid of spacing dx/2 over the fluid's padded bounding box; a grid
point is *open* when d exceeds the open radius r_o (`drop.open_radius`: 0.91 dx in 3D for link
1.5, so an intact lattice has no open point); the open points connected to the box's border are the *outside*,
each other connected set of open points (face neighbours) is a *void*, its gap 2 max d.

A particle *faces* an open region when that region has a grid point within r_o + 2 s of the
particle's grid point (s the grid spacing: the open point nearest to a particle of the region's
boundary lies between r_o and r_o + s from the particle, and the particle's grid point is up to
s √3/2 from it). The particles facing a void are its *boundary*.

Origin of a void in frame k, from its boundary particles present in frame k − 1 (ids): each is
counted as facing a void in k − 1 (any; first), else facing the outside, else inside the fluid.
- the most of them faced voids: the void *persists*, and takes the origin of the void of k − 1
  that most of them faced;
- else the most faced the outside: *enclosed* (a pocket the flow closed over the outside
  between the frames);
- else (the most were inside the fluid): *opened* inside the fluid.
A void in the first frame, or whose boundary particles are all new, is counted as opened (no
evidence of an enclosure). The classification does not depend on the output interval as long
as a pocket's boundary particles are still at the surface one frame before it closes: the
surface particles that close a pocket were at the surface before, whatever the interval.
"""
import numpy as np

ENCLOSED = "enclosed"
OPENED = "opened"


class VoidTracker:
    """Follows the voids of successive frames of one run (call `frame` in time order)."""

    def __init__(self):
        self.prev_ids = None        # sorted ids of the previous frame's particles
        self.prev_state = None      # per sorted id: -1 outside, 0 inside, v >= 1 the void it faced
        self.prev_origin = {}       # void label of the previous frame -> origin

    def frame(self, pos, ids, g):
        """The voids of this frame: a list of dicts (gap [m], origin: "enclosed" or "opened",
        persists: bool, boundary: the number of particles facing it), largest gap first.
        g: this frame's `drop.open_grid` of pos (`drop.grid_measures` returns it)."""
        from scipy import ndimage

        s, lo, shape = g["s"], g["lo"], g["shape"]
        enclosed = g["open"] & ~g["outside"]
        lab, n = ndimage.label(enclosed)
        reach = g["r_open"] + 2.0 * s
        cell = np.clip(np.rint((pos - lo) / s).astype(int), 0, np.array(shape) - 1)
        cell = tuple(cell.T)
        # per particle: the distance to the nearest outside point, and to the nearest void point
        # with that point's void label
        to_out = ndimage.distance_transform_edt(~g["outside"], sampling=s)[cell]
        state = np.where(to_out <= reach, -1, 0)
        voids = []
        if n:
            dist, near = ndimage.distance_transform_edt(lab == 0, sampling=s, return_indices=True)
            near_label = lab[tuple(near)]
            faced = np.where(dist[cell] <= reach, near_label[cell], 0)
            state = np.where(faced > 0, faced, state)
            index = np.arange(1, n + 1)
            gaps = 2.0 * np.asarray(ndimage.maximum(g["d"], lab, index))
            origins = {}
            for v, gap in zip(index, gaps):
                members = ids[faced == v]
                origin, persists = self._origin(members)
                origins[int(v)] = origin
                voids.append({"gap": float(gap), "origin": origin, "persists": persists,
                              "boundary": int(members.size)})
            self.prev_origin = origins
        else:
            self.prev_origin = {}
        order = np.argsort(ids, kind="stable")
        self.prev_ids = ids[order]
        self.prev_state = state[order]
        voids.sort(key=lambda v: -v["gap"])
        return voids

    def _origin(self, members):
        """(origin, persists) of a void whose boundary particles have these ids."""
        if self.prev_ids is None or members.size == 0:
            return OPENED, False
        k = np.searchsorted(self.prev_ids, members)
        k = np.clip(k, 0, self.prev_ids.size - 1)
        known = self.prev_ids[k] == members
        before = self.prev_state[k[known]]
        if before.size == 0:
            return OPENED, False
        faced_void = before[before > 0]
        n_out = int(np.count_nonzero(before == -1))
        n_in = int(np.count_nonzero(before == 0))
        if faced_void.size >= max(n_out, n_in):
            labels, counts = np.unique(faced_void, return_counts=True)
            return self.prev_origin.get(int(labels[np.argmax(counts)]), OPENED), True
        if n_out >= n_in:
            return ENCLOSED, False
        return OPENED, False


def largest(voids, origin):
    """The largest gap [m] among the voids of this origin (0 when none)."""
    return max((v["gap"] for v in voids if v["origin"] == origin), default=0.0)
