"""The library's importance sampler in Dr.Jit: conditional half-vector warps for the Mitsuba
plugin's JIT variants.

Why a module: the plugin used to sample wo from 2D distributions of its own (16 slices over
θi, a cosine mixture) whose weights reached 20–170 near the normal and the horizon. This is
the design of ``src/table/sampling/`` (see its module docs) on the densities the library
exports (:meth:`brdftab.Brdf.sampling_nodes`, adjoint: conditioned on wi, ∝ f_r cos θo):

- the unit square (s, y) ↦ half vector h, θh = (π/2)(a s + (1 − a) s²) (a = the nodes' ``linear``), φh = 2π y − π relative
  to φi (isotropic sources); wo = 2 (wi·h) h − wi, dωo = 4 (wi·h) sin θh dθh/ds dφh/dy ds dy;
- the densities at the nodes drawn with the library's own alias tables (``_alias2d``: the
  normalized slices interpolated linearly between conditioning nodes over t = sqrt(1 − cos θi),
  bilinearly over t and φi for anisotropic sources, the same piecewise-bilinear density as the
  library's and the RGL format's), so sample and pdf agree for every wi;
- a draw whose mirror image falls below the horizon is folded above it (z → −z), and the
  density of wo is the sum over both preimages.

Only the map, the fold and the conditioning weights are written here; the node densities and
their draw are the library's.
"""

from __future__ import annotations

import math

#: Below this s a half vector is at the pole (sampling.rs ``POLE_S``): its density is the limit
#: there, read at s = ``POLE_S``, y = ½, where the map's Jacobian (0 at the pole) is not yet 0.
POLE_S = 1e-9

#: A pair whose sum ŵi + ŵo is shorter than this has no half vector float32 can tell: at the
#: mirror direction the fold's other preimage (wo mirrored below the horizon) sums with wi to
#: the rounding of wo (~1e-7), whose "half vector" is noise and whose density (over 2 |sum|)
#: read 300 where the direction's own is 21 (paper_white). Its density is taken as 0 there, in
#: :meth:`HalfVectorSampler.sample` and :meth:`HalfVectorSampler.pdf` alike: a solid angle of
#: ~1e-12 sr, whose share of any draw is below float32's resolution of u.
MIN_SUM = 1e-6

class HalfVectorSampler:
    """Draws wo given wi ∝ f_r(wi, wo) cos θo from the library's node densities."""

    def __init__(self, nodes):
        from ._alias2d import AliasWarp2D

        if nodes.get("version") != 3:
            raise ValueError(f"sampling nodes version {nodes.get('version')!r}: expected 3")
        # The θh map's linear share (sampling.rs `HALF_MAP_LINEAR`).
        self.linear = float(nodes["linear"])
        self.nt, self.np, ny, nx = (int(nodes[k]) for k in ("nt", "np", "ny", "nx"))
        self.isotropic = bool(nodes["isotropic"]) or self.np == 1
        self.warp = AliasWarp2D(nodes["alias"], nx, ny)
        self.bytes = self.warp.bytes

    # -- the frame of the nodes ---------------------------------------------------------------
    def _frame(self, b):
        """(cos φ, sin φ) rotating into the nodes' frame (isotropic) and the conditioning
        corners: (slice, weight) pairs, linear over t = sqrt(1 − cos θ) (bilinear over t and
        φ, periodic, for anisotropic sources), as ``TableSampler`` weighs its slices."""
        import drjit as dr
        import mitsuba as mi

        F, U = type(b.x), mi.UInt32
        if self.nt == 1:
            t0, t1, ft = U(0), U(0), F(0.0)
        else:
            t = dr.sqrt(dr.maximum(1.0 - b.z, 0.0))
            st = dr.clip(t * (self.nt - 1), 0.0, float(self.nt - 1))
            t0 = dr.minimum(U(st), self.nt - 2)
            t1, ft = t0 + 1, st - F(t0)
        if self.isotropic:
            r2 = b.x * b.x + b.y * b.y
            ok = r2 > 1e-20
            inv = dr.rsqrt(dr.select(ok, r2, 1.0))
            corners = [(t0, 1.0 - ft), (t1, ft)]
            return dr.select(ok, b.x * inv, 1.0), dr.select(ok, b.y * inv, 0.0), corners
        n = self.np
        phi = dr.atan2(b.y, b.x)
        phi = dr.select(phi < 0, phi + 2 * math.pi, phi)
        sp = phi * (n / (2 * math.pi))
        p0 = dr.minimum(U(sp), n - 1)
        p1 = dr.select(p0 + 1 == n, 0, p0 + 1)
        fp = dr.clip(sp - F(p0), 0.0, 1.0)
        corners = [(t0 * n + p0, (1.0 - ft) * (1.0 - fp)), (t0 * n + p1, (1.0 - ft) * fp),
                   (t1 * n + p0, ft * (1.0 - fp)), (t1 * n + p1, ft * fp)]
        return F(1.0), F(0.0), corners

    @staticmethod
    def _rot(v, c, s):
        import mitsuba as mi

        return mi.Vector3f(c * v.x + s * v.y, -s * v.x + c * v.y, v.z)

    @staticmethod
    def _unrot(v, c, s):
        import mitsuba as mi

        return mi.Vector3f(c * v.x - s * v.y, s * v.x + c * v.y, v.z)

    @staticmethod
    def _mirror(v):
        import mitsuba as mi

        return mi.Vector3f(v.x, v.y, -v.z)

    # -- the square and the half vector (sampling.rs: half_of, square_of, half_jacobian) ----
    def _half_of(self, p):
        import drjit as dr
        import mitsuba as mi

        th = (0.5 * math.pi) * p.x * (self.linear + (1.0 - self.linear) * p.x)
        st, ct = dr.sincos(th)
        sp, cp = dr.sincos(2 * math.pi * p.y)
        return mi.Vector3f(-st * cp, -st * sp, ct), st

    def _jacobian(self, s, sin_th):
        a = self.linear
        return sin_th * (0.5 * math.pi) * (a + 2.0 * (1.0 - a) * s) * (2 * math.pi)

    def _at_pole(self, u, sin_th):
        """(u, sin θh) where the density of ``u`` is read: ``u`` itself, or within s <
        :data:`POLE_S` of the pole (the mirror direction, where the Jacobian is 0 and the
        density its limit) (``POLE_S``, ½) as sampling.rs ``pole_density`` reads it."""
        import drjit as dr
        import mitsuba as mi

        pole = u.x < POLE_S
        a = self.linear
        sin_pole = math.sin(0.5 * math.pi * POLE_S * (a + (1.0 - a) * POLE_S))
        return (mi.Point2f(dr.select(pole, POLE_S, u.x), dr.select(pole, 0.5, u.y)),
                dr.select(pole, sin_pole, sin_th))

    def _square_of(self, h):
        import drjit as dr
        import mitsuba as mi

        r = dr.sqrt(h.x * h.x + h.y * h.y)
        q = dr.atan2(r, h.z) * (2.0 / math.pi)
        a = self.linear
        s = 2.0 * q / (a + dr.sqrt(a * a + 4.0 * (1.0 - a) * q))
        y = (dr.atan2(h.y, h.x) + math.pi) * (0.5 / math.pi)
        y = y - dr.floor(y)
        return mi.Point2f(dr.clip(s, 0.0, 1.0), y), r

    def _density_at(self, h, n, corners, active):
        """Density (solid angle of the drawn direction) of drawing the half vector ``h`` (unit,
        in the nodes' frame) of a pair whose sum has length ``n`` (0: none): wi·h = n/2 for unit
        wi, wo (DESIGN: as ``dot(wi, h)`` it cancels at a grazing view)."""
        import drjit as dr

        ok = active & (n > MIN_SUM) & (h.z > 0)
        u, sin_th = self._at_pole(*self._square_of(h))
        # 4 (wi·h) = 2 n.
        d = self.warp.eval(u, corners, ok) / (2.0 * n * self._jacobian(u.x, sin_th))
        return dr.select(ok & dr.isfinite(d), d, 0.0)

    @staticmethod
    def _sums(wi, wo):
        """The half vectors (unit, float32, the caller's frame) of (wi, wo) and (wi, mirror(wo))
        with the lengths of the sums, ŵi + ŵo summed in float64 from the directions made unit
        in float64. Where wo is nearly −wi (the mirror direction at a grazing view) the sum is
        ~|wi + wo| ~ 1e-3 and float32 would leave it the error of the inputs' lengths (2⁻²⁴
        from rounding, 1e-7 after ``dr.normalize``): a tilt of h by 1e-4 rad along wi, which a
        sum of unit vectors cannot have, and 2.4 % in the density at 89.999° (measured)."""
        import drjit as dr
        import mitsuba as mi

        a, b = mi.Vector3d(wi), mi.Vector3d(wo)
        a, b = a / dr.norm(a), b / dr.norm(b)
        x, y = a.x + b.x, a.y + b.y
        out = []
        for v in (mi.Vector3d(x, y, a.z + b.z), mi.Vector3d(x, y, a.z - b.z)):
            n = dr.norm(v)
            h = v / dr.select(n > 0, n, 1.0)
            out.append((mi.Vector3f(h), mi.Float(n)))
        return out

    # -- the plugin's entry points ------------------------------------------------------------
    def sample(self, wi, u, active):
        """(wo, pdf) for unit wi above the horizon and u in [0, 1)²; pdf = 0 where no
        direction is drawn."""
        import drjit as dr

        c, s, corners = self._frame(wi)
        bl = self._rot(wi, c, s)
        p, pdf_sq = self.warp.sample(u, corners, active)
        h, sin_th = self._half_of(p)
        dot = dr.dot(bl, h)
        ok = active & (dot > 0)
        drawn = 2.0 * dot * h - bl
        # Folded at the horizon: the other preimage of the result is its mirror image.
        folded = drawn.z <= 0
        al = dr.select(folded, self._mirror(drawn), drawn)
        wo = dr.normalize(self._unrot(al, c, s))
        # Both densities from the returned wo, as `pdf` reads them: the drawn preimage's wi·h
        # as |wi + wo|/2 of the direction handed back (`dot`, rounded at a grazing view, and
        # the rounding of wo would leave sample's pdf and pdf(wi, wo) apart), the other's from
        # its sum (0 where its half vector is below the horizon).
        (hd, nd), (hm, nm) = self._sums(wi, wo)
        pole = p.x < POLE_S
        q, sin_q = self._at_pole(p, sin_th)
        pdf_sq = dr.select(pole, self.warp.eval(q, corners, ok & pole), pdf_sq)
        here = pdf_sq / (2.0 * dr.select(folded, nm, nd) * self._jacobian(q.x, sin_q))
        other = self._density_at(self._rot(dr.select(folded, hd, hm), c, s),
                                 dr.select(folded, nd, nm), corners, ok)
        pdf = here + other
        ok &= (al.z > 0) & (wo.z > 0) & (pdf > 0) & dr.isfinite(pdf)
        return wo, dr.select(ok, pdf, 0.0)

    def pdf(self, wi, wo, active):
        """The density with which :meth:`sample` draws unit wo given unit wi."""
        c, s, corners = self._frame(wi)
        (hd, nd), (hm, nm) = self._sums(wi, wo)
        return (self._density_at(self._rot(hd, c, s), nd, corners, active)
                + self._density_at(self._rot(hm, c, s), nm, corners, active))
