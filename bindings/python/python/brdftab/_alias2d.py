"""The library's constant-time draw of the sampler's piecewise-bilinear densities, in Dr.Jit.

Why a module: the plugin drew its half vectors with Mitsuba's ``MarginalContinuous2D1``: two
binary searches over CDFs interpolated between conditioning slices, a dozen dependent gathers,
about 70 % of a sample's time. The library draws the same densities with alias tables
(Rust ``src/table/alias2d/``) and exports them (``Brdf.sampling_nodes()["alias"]``, Rust
``brdftab::table::AliasTables``); this is that draw on Dr.Jit arrays, so the plugin runs the
library's sampling structure itself, not a warp of its own on the same nodes:

- the slice (conditioning node) is chosen by its interpolation weight — the interpolated
  density is the mixture of the normalized slices';
- an alias table over the slice's 2(ny − 1) half-strips gives strip j, row r = j or j + 1 and
  t across the strip (from 2t or 2(1 − t));
- row r's alias table over its nx − 1 cells gives cell c, a coin weighted by the cell's end
  densities picks 2f or 2(1 − f), and f.

The density of a point (:meth:`AliasWarp2D.eval`, and the one :meth:`AliasWarp2D.sample`
returns) is the mixture's bilinear interpolant, per unit area of the square.
"""

from __future__ import annotations

import numpy as np


class AliasWarp2D:
    """Draws points of the unit square from slices of node densities mixed by conditioning
    weights (a list of ``(slice, weight)`` pairs, Dr.Jit ``UInt32`` and ``Float``)."""

    def __init__(self, alias, nx, ny):
        import mitsuba as mi

        self.nx, self.ny = int(nx), int(ny)
        bits = int(alias["other_bits"])
        if not 1 <= bits <= 24:
            raise ValueError(f"alias tables with {bits} bits of `other`: expected 1..24")
        self.kb = 32 - bits
        pdf = np.ascontiguousarray(alias["pdf"], np.float32).ravel()
        strips = np.ascontiguousarray(alias["strips"], np.uint32).ravel()
        cells = np.ascontiguousarray(alias["cells"], np.uint32).ravel()
        plane = self.nx * self.ny
        slices = pdf.size // plane
        if (pdf.size != slices * plane or strips.size != slices * 2 * (self.ny - 1)
                or cells.size != slices * self.ny * (self.nx - 1)):
            raise ValueError("alias tables whose sizes do not match nx, ny")
        self.pdf, self.strips, self.cells = mi.Float(pdf), mi.UInt32(strips), mi.UInt32(cells)
        self.bytes = pdf.nbytes + strips.nbytes + cells.nbytes

    # -- pieces of the draw -------------------------------------------------------------------
    def _pick(self, table, base, n, u, active):
        """Slot of the alias table of ``n`` entries at ``base`` drawn by u ∈ [0, 1), and the
        remainder of u (again uniform on [0, 1))."""
        import drjit as dr
        import mitsuba as mi

        x = u * n
        i = dr.minimum(mi.UInt32(x), n - 1)
        f = x - mi.Float(i)
        e = dr.gather(mi.UInt32, table, base + i, active)
        keep = mi.Float(e & ((1 << self.kb) - 1)) * float(2.0 ** -self.kb)
        kept = f < keep
        slot = dr.select(kept, i, e >> self.kb)
        rem = dr.select(kept, f / keep, (f - keep) / (1.0 - keep))
        return slot, dr.minimum(rem, 1.0)

    @staticmethod
    def _rise_or_fall(rising, v):
        """A draw from 2t (``rising``: t = √v) or 2(1 − t) (t = 1 − √(1 − v))."""
        import drjit as dr

        q = dr.sqrt(dr.maximum(dr.select(rising, v, 1.0 - v), 0.0))
        return dr.minimum(dr.select(rising, q, 1.0 - q), 1.0)

    @staticmethod
    def _own(corners):
        """Copies of the corners' arrays: Dr.Jit may widen an operand of ``select`` in place
        (1.5 did, for a width-1 array no other variable shared), which would leave the
        caller's corners unusable with points of another count."""
        return [(type(s)(s), type(w)(w)) for s, w in corners]

    @staticmethod
    def _pick_slice(corners, v):
        """A slice by its weight (corner order) and the rescaled v."""
        import drjit as dr

        s, w = corners[0]
        lo, acc = type(v)(0.0), w
        for sn, wn in corners[1:]:
            nxt = (v >= acc) & (wn > 0)
            s = dr.select(nxt, sn, s)
            w = dr.select(nxt, wn, w)
            lo = dr.select(nxt, acc, lo)
            acc = acc + wn
        return s, dr.clip((v - lo) / w, 0.0, 1.0)

    def _mix(self, corners, c, f, j, t, active):
        """Σ weight × the slice's bilinear density in cell (c, j) at (f, t), per unit area."""
        import drjit as dr
        import mitsuba as mi

        nx = self.nx
        o = j * nx + c
        p = mi.Float(0.0)
        for s, w in corners:
            base = s * (nx * self.ny) + o
            q00 = dr.gather(mi.Float, self.pdf, base, active)
            q01 = dr.gather(mi.Float, self.pdf, base + 1, active)
            q10 = dr.gather(mi.Float, self.pdf, base + nx, active)
            q11 = dr.gather(mi.Float, self.pdf, base + nx + 1, active)
            p = p + w * ((1.0 - t) * ((1.0 - f) * q00 + f * q01)
                         + t * ((1.0 - f) * q10 + f * q11))
        return p * float((self.nx - 1) * (self.ny - 1))

    # -- the warp ------------------------------------------------------------------------------
    def sample(self, u, corners, active):
        """(point of the unit square, its density) for u ∈ [0, 1)²: u.y picks the slice, the
        half-strip and t; u.x the cell, the coin and f."""
        import drjit as dr
        import mitsuba as mi

        nx, ny = self.nx, self.ny
        corners = self._own(corners)
        s, v = self._pick_slice(corners, u.y)
        hy = 2 * (ny - 1)
        h, v = self._pick(self.strips, s * hy, hy, v, active)
        j, odd = h >> 1, h & 1
        t = self._rise_or_fall(odd == 1, v)
        r = j + odd
        c, x = self._pick(self.cells, (s * ny + r) * (nx - 1), nx - 1, u.x, active)
        base = s * (nx * ny) + r * nx + c
        a = dr.gather(mi.Float, self.pdf, base, active)
        b = dr.gather(mi.Float, self.pdf, base + 1, active)
        x = x * (a + b)
        right = (x >= a) & (b > 0)
        q = dr.select(right, x - a, x) / dr.select(right, b, a)
        # In [0, 1] up to rounding; NaN (0/0, an empty row) becomes 0.
        q = dr.select(q >= 0, dr.minimum(q, 1.0), 0.0)
        f = self._rise_or_fall(right, q)
        point = mi.Point2f((mi.Float(c) + f) / (nx - 1), (mi.Float(j) + t) / (ny - 1))
        return point, self._mix(corners, c, f, j, t, active)

    def eval(self, u, corners, active):
        """The density of :meth:`sample` at the point u of the unit square."""
        import drjit as dr
        import mitsuba as mi

        def locate(x, n):
            p = x * (n - 1)
            i = dr.select(p > 0, dr.minimum(mi.UInt32(p), n - 2), 0)
            return i, p - mi.Float(i)

        corners = self._own(corners)
        c, f = locate(u.x, self.nx)
        j, t = locate(u.y, self.ny)
        return self._mix(corners, c, f, j, t, active)
