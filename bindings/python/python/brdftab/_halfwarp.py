"""The library's importance sampler in Dr.Jit: conditional half-vector warps for the Mitsuba
plugin's JIT variants.

Why a module: the plugin used to sample wo from 2D distributions of its own (16 slices over
θi, a cosine mixture) whose weights reached 20–170 near the normal and the horizon. This is
the design of ``src/table/sampling.rs`` (see its module docs) on the densities the library
exports (:meth:`brdftab.Brdf.sampling_nodes`, adjoint: conditioned on wi, ∝ f_r cos θo):

- the unit square (s, y) ↦ half vector h, θh = (π/2)(0.1 s + 0.9 s²), φh = 2π y − π relative
  to φi (isotropic sources); wo = 2 (wi·h) h − wi, dωo = 4 (wi·h) sin θh dθh/ds dφh/dy ds dy;
- the densities at the nodes as Mitsuba's ``MarginalContinuous2D1`` over t = sqrt(1 − cos θi)
  (``MarginalContinuous2D2`` over t and φi for anisotropic sources, the first φ slice repeated
  at 2π), the same piecewise-bilinear warp as the library's and the RGL format's, interpolated
  linearly between conditioning nodes, so sample and pdf agree for every wi;
- a draw whose mirror image falls below the horizon is folded above it (z → −z), and the
  density of wo is the sum over both preimages.

Only the map and the fold are written here; the node densities are the library's.
"""

from __future__ import annotations

import math

import numpy as np

_LINEAR = 0.1  # sampling.rs `LINEAR`


class HalfVectorSampler:
    """Draws wo given wi ∝ f_r(wi, wo) cos θo from the library's node densities."""

    def __init__(self, nodes):
        import mitsuba as mi

        if nodes.get("version") != 1:
            raise ValueError(f"sampling nodes version {nodes.get('version')!r}: expected 1")
        nt, np_, ny, nx = (int(nodes[k]) for k in ("nt", "np", "ny", "nx"))
        data = np.asarray(nodes["data"], np.float32).reshape(nt, np_, ny, nx)
        if nt == 1:  # one node (t = ½): Mitsuba wants two parameter values
            data = np.concatenate([data, data], 0)
            t = [0.0, 1.0]
        else:
            t = np.linspace(0.0, 1.0, nt).tolist()
        self.isotropic = bool(nodes["isotropic"]) or np_ == 1
        if self.isotropic:
            self.warp = mi.MarginalContinuous2D1(data[:, 0], [t], normalize=True)
        else:
            # Periodic over φi: the first slice again at 2π.
            data = np.concatenate([data, data[:, :1]], 1)
            phi = (np.arange(np_ + 1) * (2 * math.pi / np_)).tolist()
            self.warp = mi.MarginalContinuous2D2(data, [t, phi], normalize=True)
        self.bytes = data.nbytes

    # -- the frame of the nodes ---------------------------------------------------------------
    def _frame(self, b):
        """(cos φ, sin φ) rotating into the nodes' frame (isotropic) and the warp's parameters."""
        import drjit as dr

        t = dr.sqrt(dr.maximum(1.0 - b.z, 0.0))
        t = dr.minimum(t, 1.0)
        if self.isotropic:
            r2 = b.x * b.x + b.y * b.y
            ok = r2 > 1e-20
            inv = dr.rsqrt(dr.select(ok, r2, 1.0))
            return dr.select(ok, b.x * inv, 1.0), dr.select(ok, b.y * inv, 0.0), [t]
        phi = dr.atan2(b.y, b.x)
        phi = dr.select(phi < 0, phi + 2 * math.pi, phi)
        return type(b.x)(1.0), type(b.x)(0.0), [t, phi]

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
    @staticmethod
    def _half_of(p):
        import drjit as dr
        import mitsuba as mi

        th = (0.5 * math.pi) * p.x * (_LINEAR + (1.0 - _LINEAR) * p.x)
        st, ct = dr.sincos(th)
        sp, cp = dr.sincos(2 * math.pi * p.y)
        return mi.Vector3f(-st * cp, -st * sp, ct), st

    @staticmethod
    def _jacobian(s, sin_th):
        return sin_th * (0.5 * math.pi) * (_LINEAR + 2.0 * (1.0 - _LINEAR) * s) * (2 * math.pi)

    @staticmethod
    def _square_of(h):
        import drjit as dr
        import mitsuba as mi

        r = dr.sqrt(h.x * h.x + h.y * h.y)
        q = dr.atan2(r, h.z) * (2.0 / math.pi)
        s = 2.0 * q / (_LINEAR + dr.sqrt(_LINEAR * _LINEAR + 4.0 * (1.0 - _LINEAR) * q))
        y = (dr.atan2(h.y, h.x) + math.pi) * (0.5 / math.pi)
        y = y - dr.floor(y)
        return mi.Point2f(dr.clip(s, 0.0, 1.0), y), r

    def _density_at(self, al, bl, param, active):
        """Density (solid angle of al) of drawing the half vector of (al, bl), nodes' frame."""
        import drjit as dr

        h = al + bl
        n2 = dr.squared_norm(h)
        ok = active & (n2 > 0)
        h = h * dr.rsqrt(dr.select(ok, n2, 1.0))
        dot = dr.dot(bl, h)
        ok &= (h.z > 0) & (dot > 0)
        u, sin_th = self._square_of(h)
        d = self.warp.eval(u, param, ok) / (4.0 * dot * self._jacobian(u.x, sin_th))
        return dr.select(ok & dr.isfinite(d), d, 0.0)

    # -- the plugin's entry points ------------------------------------------------------------
    def sample(self, wi, u, active):
        """(wo, pdf) for unit wi above the horizon and u in [0, 1)²; pdf = 0 where no
        direction is drawn."""
        import drjit as dr

        c, s, param = self._frame(wi)
        bl = self._rot(wi, c, s)
        p, pdf_sq = self.warp.sample(u, param, active)
        h, sin_th = self._half_of(p)
        dot = dr.dot(bl, h)
        ok = active & (dot > 0)
        drawn = 2.0 * dot * h - bl
        here = pdf_sq / (4.0 * dot * self._jacobian(p.x, sin_th))
        # Folded at the horizon: the other preimage of the result is its mirror image. Above,
        # the mirror of `drawn` has a density only when drawn.z < wi.z (else its half vector is
        # below the horizon and `_density_at` gives 0); below, the result is mirror(drawn).
        other = self._density_at(self._mirror(drawn), bl, param, ok)
        al = dr.select(drawn.z > 0, drawn, self._mirror(drawn))
        pdf = here + other
        ok &= (al.z > 0) & (pdf > 0) & dr.isfinite(pdf)
        wo = dr.normalize(self._unrot(al, c, s))
        return wo, dr.select(ok, pdf, 0.0)

    def pdf(self, wi, wo, active):
        """The density with which :meth:`sample` draws unit wo given unit wi."""
        c, s, param = self._frame(wi)
        bl, al = self._rot(wi, c, s), self._rot(wo, c, s)
        return (self._density_at(al, bl, param, active)
                + self._density_at(self._mirror(al), bl, param, active))
