"""A Mitsuba 3 BSDF plugin ``brdftab`` over any brdftab SOURCE.

>>> import mitsuba as mi, brdftab.mitsuba
>>> mi.set_variant("scalar_rgb")
>>> brdftab.mitsuba.register()
>>> bsdf = mi.load_dict({"type": "brdftab", "source": "paper_white_rgb.bsdf"})  # doctest: +SKIP

Properties: ``source`` (string, any SOURCE: spec, table, ``DB#NAME``, MERL, RGL; or
``filename``, the name Mitsuba's own file-reading plugins such as ``measured`` use), optional
``interp`` (``"auto"``, the default: nearest on tables of MERL cells as every host of the
library reads them, linear otherwise; or ``"linear"`` or ``"nearest"``), and for JIT variants optional ``preset`` / ``grid``
(the table a non-table source is baked on — given with a table source they are an error in
every variant; default: for an isotropic model the smallest
adaptive grid within :data:`MODEL_TARGET_ERROR`, calibrated to the model's albedo, for other
models the library's default bake — the ``medium`` preset, calibrated where its albedo misses
the model's by over 1 % (Ward's anisotropic lobes at the horizon); RGL files: the library's adaptive grid, MERL files: their own cells),
``sampling_res`` (the
resolution of the sampling distributions: half-vector nodes per axis; default the library's,
:meth:`brdftab.Brdf.sampling_resolution`: 64, 128 θh nodes for a peak too sharp for 64, 48 for
anisotropic tables; an integer from 16 to 1024, checked in every variant), ``cache`` (bool —
or a string that says one, ``"false"`` —, default
true: baked tables are kept in the cache of baked tables, :func:`brdftab.bake_cached`, so a
material is baked once, not at every scene load) and ``cache_dir``.

Conventions are those of Mitsuba's ``measured`` plugin: ``si.wi`` is brdftab's ``wi`` (towards
the light in brdftab's words; the tensor's incident axes for RGL data), Mitsuba's ``wo`` is
brdftab's ``wo``; ``eval`` returns f_r · cos θ(wo); front side only (so a source that transmits
— a refractor — is refused: use Mitsuba's ``dielectric``). In importance transport
(``BSDFContext(TransportMode.Importance)``, a light tracer such as ``ptracer``) ``eval`` and
``sample``'s weight are the adjoint, f_r(wo, si.wi) · cos θ(wo), so ``path`` and ``ptracer``
render one material also for a source that is not reciprocal (the sampler and ``pdf`` are the
same in both modes). The plugin is one component (index 0) with the source's lobe flags: a
context whose type mask or component leaves it out gets zeros, as from Mitsuba's plugins (for
``eval``/``pdf`` its smooth lobes count, for ``sample`` any of them: a sum's draw is not split
by lobe). In a polarized variant the plugin is a depolarizer (f_r cos θo in the Mueller
matrix's first entry, as Mitsuba's ``measured`` and ``diffuse``: a source says nothing of
polarization); in a monochrome variant (``llvm_ad_mono``) an RGB source is read as its
luminance, as Mitsuba reads RGB inputs there.

- Scalar variants (``scalar_rgb``, ``scalar_spectral``) call the library for every query (the
  native source: RGL files evaluate with their own adaptive parameterization, as Mitsuba's
  ``measured`` does — so within ~5° of normal incidence, where an RGL file has no single value
  and a table holds the azimuthal mean of its normal slice (README, "At normal incidence"),
  the scalar and JIT variants differ by up to a third on some files). Delta lobes — a
  mirror, or a sum's mirror term — are delta samples (``DeltaReflection``, pdf the probability
  of choosing the lobe, weight the library's: in a spectral variant its reflectance at each of
  the path's wavelengths, :meth:`brdftab.Brdf.sample` with ``nm``); smooth draws carry the
  smooth lobes' flags.
- In a spectral variant an RGB source is read at each wavelength as the library reads RGB
  channels (:func:`brdftab.rgb_basis`: a spectrum whose colour, as the variant's film shows it,
  is the source's RGB), in the scalar and the JIT variants; the JIT variants keep such a source
  (and a model whose spectrum is the basis mix of its RGB) an RGB table.
- JIT variants (``llvm_ad_rgb``, ``cuda_ad_rgb``; sources with a delta lobe are refused: a
  table cannot hold one) cannot call back into the host per query:
  the plugin bakes (or loads) a table, uploads the library's *device layout* of it once
  (``Table.device_layout``, Rust ``src/table/device.rs``: the kernel's knot lines and packed
  values, or a dense grid with its folds and axis mappings) and evaluates that layout in Dr.Jit
  operations (:class:`JitTable`), tested equal to the Rust lookup to 1e-5 for every table kind.
  Sampling is the library's (``src/table/sampling/``): wo is drawn as the mirror image of
  wi about a half vector from conditional 2D warps of f_r cos θo over the half vector, on the
  node densities the library exports (``Brdf.sampling_nodes``), conditioned on θi (and φi for
  anisotropic tables), drawn with the library's own alias tables (``brdftab._alias2d``), with
  the exactly consistent pdf (``brdftab._halfwarp``).
- In JIT variants the table's values are a differentiable scene parameter, ``values``
  (``mi.traverse``; the table's stored values before its albedo calibration, as the layout
  holds them): eval, eval_pdf and sample's weight are linear in them, so an inverse-rendering
  loop optimizes a table like a texture (``bindings/python/examples/optimize_values.py``).
  Edited values are read as float32 (the packed f16 codes of an adaptive table give way, at
  some cost per lookup); the sampling distributions stay those of the loaded table until
  ``resample()`` rebuilds them from the current values. ``export_table()`` gives the edited
  table as a :class:`brdftab.Table` to save.
"""

from __future__ import annotations

import math
import os

import numpy as np

import brdftab
from brdftab._halfwarp import HalfVectorSampler

_REGISTERED = set()

#: The wavelengths (nm, 1 nm apart) at which the JIT path tabulates :func:`brdftab.rgb_basis`
#: to read RGB tables in spectral variants (held at the ends outside, as the library holds it).
_BASIS_NM = np.arange(360.0, 831.0)

#: The error target of the JIT variants' tables of isotropic models (relative RMSE of
#: f_r cos θi cos θo, ``brdftab.bake``'s ``target_error``). The medium preset (4.4 M values,
#: 17.7 MB in float32) made a render's table lookups miss the CPU caches: GGX copper α = 0.1
#: at this target is 288 k values with the same albedo and within-80° figures, and renders
#: 1.2–1.35× as fast (BENCHMARKS.md, "Model tables sized for a renderer").
MODEL_TARGET_ERROR = 0.002


def register():
    """Registers the plugin ``brdftab`` for the current Mitsuba variant (set one first)."""
    import mitsuba as mi

    variant = mi.variant()
    if variant is None:
        raise RuntimeError("brdftab.mitsuba.register(): call mitsuba.set_variant(...) first")
    mi.register_bsdf("brdftab", lambda props: plugin_class()(props))
    _REGISTERED.add(variant)


_CLASSES = {}


def plugin_class():
    """The plugin's class for the current variant (a subclass of that variant's ``mi.BSDF``)."""
    import drjit as dr
    import mitsuba as mi

    variant = mi.variant()
    if variant not in _CLASSES:
        mixin = JitBrdftabBSDF if dr.is_jit_v(mi.Float) else ScalarBrdftabBSDF
        # nanobind classes take one base: the methods of the mixins are copied in.
        ns = {"_base": mi.BSDF}
        for cls in reversed(mixin.__mro__[:-1]):
            ns.update({k: v for k, v in vars(cls).items() if not k.startswith("__") or k == "__init__"})
        _CLASSES[variant] = type("BrdftabBSDF", (mi.BSDF,), ns)
    return _CLASSES[variant]


def _prop(props, name, default=None):
    try:
        if name in props:
            return props[name]
        return default
    except Exception:  # older Properties API
        pass
    try:
        return props.get(name, default)
    except Exception:
        return default


def _flags(brdf, source):
    """Mitsuba's BSDF flags from the lobes the library declares (`Brdf.flags["lobes"]`)."""
    import mitsuba as mi

    F = mi.BSDFFlags
    lobes = brdf.flags["lobes"]
    flags = F.FrontSide
    if lobes["delta"]:
        flags |= F.DeltaReflection  # transmitting sources are refused
    if lobes["diffuse"]:
        flags |= F.DiffuseReflection
    if lobes["glossy"] or not (lobes["delta"] or lobes["diffuse"]):
        flags |= F.GlossyReflection
    return flags


JIT_TABLE_PROPERTIES = ("preset", "grid", "cache", "cache_dir", "sampling_res")
"""Properties of the JIT variants' table (how a non-table source is baked, where the bake is
cached, the sampler's resolution). The scalar variants accept them and ignore them — they
evaluate the source itself — but check ``preset``, ``grid``, ``cache`` and ``sampling_res`` as
the JIT variants do."""


#: The range of the ``sampling_res`` property (half-vector nodes per axis). Below 16 the JIT
#: draw's density and ``pdf`` drift apart in float32 (0.9 % at 8 nodes, 5.7x at 2); 16 keeps
#: them within 1e-4, as the default does.
SAMPLING_RES_RANGE = (16, 1024)


def _bool_prop(props, name, default):
    """A boolean property: a bool (XML ``<boolean>``), or a string or 0/1 that says one (XML
    ``<string>``: ``bool("no")`` was true)."""
    v = _prop(props, name, default)
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)) and v in (0, 1):
        return bool(v)
    if isinstance(v, str) and v.strip().lower() in ("true", "yes", "on", "1"):
        return True
    if isinstance(v, str) and v.strip().lower() in ("false", "no", "off", "0"):
        return False
    raise ValueError(f"brdftab plugin: `{name}` must be a boolean, got {v!r}")


def _sampling_res_prop(props):
    """The ``sampling_res`` property: None, or an integer within :data:`SAMPLING_RES_RANGE`."""
    v = _prop(props, "sampling_res")
    if v is None:
        return None
    lo, hi = SAMPLING_RES_RANGE
    try:
        n = int(v)
        whole = float(v) == n
    except (TypeError, ValueError, OverflowError):
        whole = False
    if not whole or not lo <= n <= hi:
        raise ValueError(
            f"brdftab plugin: `sampling_res` must be an integer from {lo} to {hi} (half-vector "
            f"nodes per axis), got {v!r}"
        )
    return n


def _cache_dir_prop(props):
    """The ``cache_dir`` property: None (the library's default cache) or a directory's path as
    a string; anything else is refused in every variant (the scalar ones took ``cache_dir: 5``
    that the JIT ones refused with a bare TypeError)."""
    v = _prop(props, "cache_dir")
    if v is None:
        return None
    if isinstance(v, os.PathLike):
        v = os.fspath(v)
    if not isinstance(v, str) or not v.strip():
        raise ValueError(
            f"brdftab plugin: `cache_dir` must be a directory's path (a non-empty string), got "
            f"{type(v).__name__} {v!r}"
        )
    return v


def _check_bake_props(props, source):
    """Refuses ``preset``/``grid`` values the JIT variants' bake would refuse, without baking."""
    options = {k: str(_prop(props, k)) for k in ("preset", "grid") if _prop(props, k) is not None}
    if options:
        brdftab._native._check_bake_options(source, **options)


def brdftab_kind(source):
    """The kind of SOURCE as the library classifies it: "spec", "merl", "rgl" or "table".

    A ``DB.btdb#NAME`` is a table whatever its name ends with (``db.btdb#paper.bsdf`` is the
    stored table named ``paper.bsdf``, not an RGL file to bake again).
    """
    return brdftab._native._source_kind(source.strip())


def _resolve(source):
    """SOURCE with its file found as Mitsuba finds files: through the file resolver, which holds
    the scene file's directory while a scene loads (so ``filename="paper.bsdf"`` beside the
    scene works as it does for ``measured``). A path part of ``DB#NAME`` is resolved alike;
    inline specs and names the resolver does not find are left as they are."""
    import mitsuba as mi

    if source.lstrip().startswith("{"):
        return source
    resolver = mi.file_resolver() if hasattr(mi, "file_resolver") else (
        mi.Thread.thread().file_resolver())

    def found(path):
        r = str(resolver.resolve(path))
        return r if os.path.exists(r) else None

    whole = found(source)
    if whole is not None:
        return whole
    head, sep, name = source.rpartition("#")
    if sep and "/" not in name:
        db = found(head)
        if db is not None:
            return f"{db}#{name}"
    return source


class _Common:
    """What both plugin flavours share: properties, flags, description."""

    def _init_common(self, props):
        import mitsuba as mi

        src, filename = _prop(props, "source"), _prop(props, "filename")
        if src is not None and filename is not None:
            raise ValueError("brdftab plugin: give `source` or `filename`, not both")
        # `filename`: what a scene written for Mitsuba's `measured` says (one word changed).
        key, src = ("filename", filename) if filename is not None else ("source", src)
        if src is None:
            raise ValueError(
                "brdftab plugin: the string property `source` (or `filename`) is required"
            )
        if isinstance(src, os.PathLike):
            src = os.fspath(src)
        if not isinstance(src, str):
            # Named as given: `filename: 3.5` was read as the file "3.5", `source: 3` said the
            # property was missing.
            raise ValueError(
                f"brdftab plugin: `{key}` must be a string, got {type(src).__name__} {src!r}"
            )
        if not src.strip():
            raise ValueError(f"brdftab plugin: `{key}` is empty")
        given = src
        src = _resolve(src)
        try:
            kind = brdftab_kind(src)
        except brdftab.Error as e:
            raise brdftab.Error(f"brdftab plugin: `{key}` {given!r}: {e}") from e
        bake = [k for k in ("preset", "grid") if _prop(props, k) is not None]
        if bake and kind == "table":
            # The JIT variants baked the table again from itself (a resample) where the scalar
            # ones read it as stored: one scene, two materials. Refused in both.
            raise ValueError(
                f"brdftab plugin: {src} is a table, evaluated as it is stored; `{bake[0]}` "
                "chooses the table a non-table source is baked on (bake the table again with "
                "brdftab.bake to change its grid)"
            )
        self.source = src
        self.interp = str(_prop(props, "interp", "auto"))
        self.spectral = mi.is_spectral
        try:
            self.brdf = brdftab.open(src, interp=self.interp)
        except brdftab.Error as e:
            # Which property named what (a file not found beside the scene, a bad spec).
            raise brdftab.Error(f"brdftab plugin: `{key}` {given!r}: {e}") from e
        if self.brdf.flags["transmission"]:
            # Every draw of a refractor lies below the surface, where this front-side BRDF
            # plugin gives nothing: it rendered black.
            raise brdftab.Error(
                f"{src}: the source transmits light (a refractor); the plugin is a BRDF (front "
                "side only): use Mitsuba's dielectric for the interface"
            )
        if not self.spectral and list(self.brdf.channels) != ["R", "G", "B"]:
            # Three wavelengths are not R, G, B: read in order they would be B, G, R at best.
            raise brdftab.Error(
                f"{src}: channels {' '.join(self.brdf.channels)}; an RGB variant needs R, G, B "
                "(use a spectral variant)"
            )
        flags = _flags(self.brdf, src)
        self.m_components = [flags]
        self.m_flags = flags
        self.delta = self.brdf.flags["delta"]

    def _enabled(self, ctx, smooth):
        """Whether ``ctx`` (its type mask and component index) asks for the plugin's one
        component, as Mitsuba's plugins check it (``ctx.is_enabled``): for ``eval`` and ``pdf``
        (``smooth``) its smooth lobes, for ``sample`` any of its lobes. A context that leaves it
        out gets zeros, not the whole BSDF."""
        import mitsuba as mi

        F = mi.BSDFFlags
        lobes = int(self.m_flags) & ~(int(F.FrontSide) | int(F.BackSide))
        if smooth:
            lobes &= int(F.Smooth)
        # `BSDFContext::is_enabled(lobes, 0)`, by hand: its Python binding takes one flag, not
        # a union of them.
        return bool(int(ctx.type_mask) & lobes) and int(ctx.component) in (0, 2**32 - 1)

    @staticmethod
    def _unpolarized(value):
        """The variant's ``UnpolarizedSpectrum`` of ``value`` (the source's channels: R, G, B, or
        the path's wavelengths in a spectral variant); in a monochrome variant the RGB value's
        luminance, as Mitsuba reads RGB inputs there."""
        import mitsuba as mi

        if mi.is_monochromatic:
            return mi.UnpolarizedSpectrum(mi.luminance(mi.Color3f(*value)))
        return mi.UnpolarizedSpectrum(value)

    @staticmethod
    def _spectrum(value):
        """The variant's ``Spectrum`` of an unpolarized value: in a polarized variant (whose
        Spectrum is a Mueller matrix) a depolarizer, as Mitsuba's ``measured`` and ``diffuse``
        give — the source says nothing of polarization."""
        import mitsuba as mi

        return mi.depolarizer(value) if mi.is_polarized else value

    @staticmethod
    def _adjoint(ctx):
        """Whether ``ctx`` is importance transport (a light tracer: ``si.wi`` points to the
        light's side of the path), where the plugin gives the adjoint BSDF f(wo, si.wi)."""
        import mitsuba as mi

        return ctx.mode == mi.TransportMode.Importance

    def to_string(self):
        """``BrdftabBSDF[source=..., <the source's description>]`` (Mitsuba's ``str``)."""
        return f"BrdftabBSDF[source={self.source!r}, {self.brdf.describe()}]"


class ScalarBrdftabBSDF(_Common):
    """Scalar variants: every query calls the library (the native source)."""

    def __init__(self, props):
        self._base.__init__(self, props)
        self._init_common(props)
        # The JIT variants' table properties are read (so that a scene written for them loads
        # here, where Mitsuba refuses a property nobody reads) and have no effect: a scalar
        # variant evaluates and samples the source itself, not a table baked from it.
        for key in JIT_TABLE_PROPERTIES:
            _prop(props, key)
        # Checked as the JIT variants check them, so a scene loads in both or in neither:
        # `preset`/`grid` as the bake would take them (a scene with `preset: "huge"` loaded
        # here and failed in a JIT variant).
        _bool_prop(props, "cache", True)
        _cache_dir_prop(props)
        _sampling_res_prop(props)
        _check_bake_props(props, self.source)

    def _f(self, wi, wo, si):
        import mitsuba as mi

        if self.spectral:
            nm = [float(x) for x in si.wavelengths]
            return self._unpolarized(self.brdf.eval_spectral(wi, wo, nm).tolist())
        return self._unpolarized(self.brdf.eval(wi, wo).tolist())

    @staticmethod
    def _vec(v):
        return [float(v[0]), float(v[1]), float(v[2])]

    def eval(self, ctx, si, wo, active=True):
        """f_r · cos θ(wo) (Mitsuba's ``eval``): 0 below either horizon and for a delta source."""
        import mitsuba as mi

        wi, wo = self._vec(si.wi), self._vec(wo)
        if self.delta or not (wi[2] > 0 and wo[2] > 0) or not active:
            return mi.Spectrum(0.0)
        if not self._enabled(ctx, True):
            return mi.Spectrum(0.0)
        cos_o = wo[2] / math.sqrt(wo[0] ** 2 + wo[1] ** 2 + wo[2] ** 2)
        if not cos_o > 0:
            # A NaN or infinite component of wo (the library's f_r is 0 for it, but 0 · NaN is
            # NaN): 0, the NaN rule of every host.
            return mi.Spectrum(0.0)
        f = self._f(wo, wi, si) if self._adjoint(ctx) else self._f(wi, wo, si)
        return self._spectrum(f * cos_o)

    def pdf(self, ctx, si, wo, active=True):
        """The density of :meth:`sample` drawing wo given ``si.wi`` (0 for a delta source)."""
        wi, wo = self._vec(si.wi), self._vec(wo)
        if self.delta or not (wi[2] > 0 and wo[2] > 0) or not active:
            return 0.0
        if not self._enabled(ctx, True):
            return 0.0
        # Mitsuba's wo is drawn given si.wi: brdftab's sampler draws its `wi` given its `wo`,
        # so it is asked with the roles swapped (see `sample`).
        return float(self.brdf.pdf(wo, wi))

    def eval_pdf(self, ctx, si, wo, active=True):
        """``(eval(...), pdf(...))``."""
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        """A ``BSDFSample3f`` and its weight f_r · cos θ(wo) / pdf, drawn by the library's
        sampler; a delta lobe's draw is a ``DeltaReflection`` sample."""
        import mitsuba as mi

        bs = mi.BSDFSample3f()
        wi = self._vec(si.wi)
        # Within [0, 1): a NaN becomes 0 (max keeps its first argument when the other is NaN).
        u = [max(0.0, min(float(x), 0.99999994)) for x in (sample2[0], sample2[1])]
        if not (wi[2] > 0) or not active or not self._enabled(ctx, False):
            return bs, mi.Spectrum(0.0)
        # A spectral variant asks for the weights at the path's wavelengths (a mirror's
        # reflectance lives only in its sample); `delta` tells a delta lobe's draw (a mirror, or
        # a sum's mirror term) from a smooth one.
        nm = [float(x) for x in si.wavelengths] if self.spectral else None
        d, pdf, w, delta = self.brdf.sample(wi, u, nm=nm, delta=True)
        pdf = float(pdf)
        if not (pdf > 0 and d[2] > 0):
            return bs, mi.Spectrum(0.0)
        bs.wo = mi.Vector3f(*[float(x) for x in d])
        bs.eta = 1.0
        bs.sampled_component = 0
        if delta:
            # pdf: the probability of choosing the delta lobe (1 for a mirror alone), as
            # Mitsuba's BSDFs with a delta component report it; the weight is the library's.
            bs.pdf = pdf
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DeltaReflection)
            return bs, self._spectrum(self._unpolarized(w.tolist()))
        bs.pdf = pdf
        # A smooth draw: the smooth lobes' flags (a sum's mirror term is not what drew it, and a
        # Delta bit would tell the integrator to skip multiple importance sampling).
        not_drawn = int(mi.BSDFFlags.FrontSide) | int(mi.BSDFFlags.Delta)
        bs.sampled_type = mi.UInt32(+self.m_flags & ~not_drawn)
        # The weight is recomputed from eval: exact also for sources that are not reciprocal.
        value = self.eval(ctx, si, bs.wo)
        return bs, value * (1.0 / pdf)

    def traverse(self, callback):
        """Nothing to expose: a scalar variant evaluates the source, which holds no values."""
        pass

    def parameters_changed(self, keys):
        """Nothing to update (see :meth:`traverse`)."""
        pass


# ---- JIT variants: the table in Dr.Jit ------------------------------------------------------

def _fast_acos(x):
    """symmetry.rs `fast_acos` (Abramowitz & Stegun 4.4.46, |error| <= 2e-8), in Dr.Jit."""
    import drjit as dr

    a = dr.minimum(dr.abs(x), 1.0)
    p = -0.0012624911
    p = p * a + 0.0066700901
    p = p * a - 0.0170881256
    p = p * a + 0.0308918810
    p = p * a - 0.0501743046
    p = p * a + 0.0889789874
    p = p * a - 0.2145988016
    p = p * a + 1.5707963050
    r = dr.sqrt(1.0 - a) * p
    return dr.select(x < 0, math.pi - r, r)


def _fast_atan2(y, x):
    """symmetry.rs `fast_atan2` (Cephes atanf reduction, |error| <= 2e-7), in Dr.Jit."""
    import drjit as dr

    ax, ay = dr.abs(x), dr.abs(y)
    swap = ay > ax
    num, den = dr.select(swap, ax, ay), dr.select(swap, ay, ax)
    z = dr.select(den > 0, num / dr.select(den > 0, den, 1.0), 0.0)
    big = z > 0.414213562373095
    # Typed: a select of two Python floats would be the variant's Float (float32), and π/4
    # rounded to float32 is 2.2e-8 off (the 5e-4 mismatch of issue 26 at φ nodes).
    F = type(z)
    base = dr.select(big, F(math.pi / 4), F(0.0))
    t = dr.select(big, (z - 1.0) / (z + 1.0), z)
    t2 = t * t
    r = base + (((8.05374449538e-2 * t2 - 1.38776856032e-1) * t2 + 1.99777106478e-1) * t2
                - 3.33329491539e-1) * t2 * t + t
    r = dr.select(swap, math.pi / 2 - r, r)
    r = dr.select(x < 0, math.pi - r, r)
    return dr.select(y < 0, -r, r)


def _packed_codes(values, channels):
    """A kernel table's values as f16 codes in 64-bit words, one word per node (channels
    padded to four), when they are f16 values scaled by one power of two — the kernel's
    ``Packed`` (table/kernel/packed.rs) of adaptive tables — and have at most four channels;
    else None.

    Returns (words, scale): a lookup gathers node n's word, moves each code's bits into a
    float32's (sign to bit 31, exponent and mantissa shifted by 13: the code's value times
    2⁻¹¹², exact for every normal code; a subnormal code, which that would make a float32
    subnormal the backend flushes, is read as its mantissa times 2⁻²⁴) and multiplies by ``scale`` =
    2¹¹² × the table's power of two, also exact: the values the lookup blends are bit for bit the
    float32 values of the layout. Why: gathers of float32 channels (3 per node, 24 per lookup)
    and their 12 bytes per node were most of a lookup's time in a render (BENCHMARKS.md).
    """
    import drjit as dr
    import mitsuba as mi

    if channels > 4 or values.size == 0 or not np.all(np.isfinite(values)):
        return None
    top = float(np.abs(values).max())
    if top == 0.0:
        return None
    e0 = int(np.floor(np.log2(65504.0 / top)))
    for e in (e0, e0 - 1, e0 + 1, e0 - 2):
        scaled = values * np.float32(2.0**e)
        if not np.all(np.abs(scaled) <= 65504.0):
            continue
        codes = scaled.astype(np.float16)
        if np.array_equal(codes.astype(np.float32), scaled):
            four = np.zeros((values.size // channels, 4), np.uint16)
            four[:, :channels] = codes.view(np.uint16).reshape(-1, channels)
            words = dr.uint64_array_t(mi.Float)(four.reshape(-1).view(np.uint64))
            return words, float(2.0 ** (112 - e))
    return None


def _unit(v, keep_unit):
    """geometry.rs ``normalize`` (v / |v|, component by component) or, with ``keep_unit``,
    ``unit`` (v as is when |v|² is 1 within 2^-40); float64 components and the validity mask
    (|v|² > 0)."""
    import drjit as dr

    n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    length = dr.sqrt(dr.maximum(n2, 1e-300))
    u = [c / length for c in v]
    if keep_unit:
        near = dr.abs(n2 - 1.0) <= 2.0**-40
        u = [dr.select(near, c, x) for c, x in zip(v, u)]
    return u, n2 > 0


def _finite(w):
    """Where every component of the direction ``w`` is finite (a NaN or infinite one makes its
    f_r 0, but 0 · NaN is NaN: the callers' ``active`` drops such lanes, 0 being the NaN rule
    of every host)."""
    import drjit as dr

    return dr.isfinite(w.x) & dr.isfinite(w.y) & dr.isfinite(w.z)


def _normalize(w):
    """``dr.normalize(w)`` that holds for any finite nonzero ``w``: scaled by its largest
    component first, so a tiny (or huge) direction whose float32 |w|² underflows (overflows)
    keeps its direction, as the library and the scalar variants take it."""
    import drjit as dr

    m = dr.maximum(dr.maximum(dr.abs(w.x), dr.abs(w.y)), dr.abs(w.z))
    return dr.normalize(w / m)


#: The version of the library's device layout (``Table.device_layout()``) this code implements.
LAYOUT_VERSION = 1


class JitTable:
    """A brdftab table uploaded to Dr.Jit and evaluated with Dr.Jit operations: an
    implementation of the library's *device layout* (``Table.device_layout(interp)``, Rust
    ``brdftab::table::device``), whose reference evaluator ``DeviceLayout::eval`` is tested equal
    to the library's table lookup. Two layouts:

    - ``kernel`` (``KernelLayout``): warp variables in float32 from the unit vectors, per axis a
      knot line giving the fractional node index, eight corners; for a resampled axis, pairs at
      or beyond its cut take the ``grid`` layout beside it;
    - ``grid`` (``GridLayout``): canonical coordinates (float64, the symmetry folds), per stored
      axis its mapping and node placement, the nearest node or 16 corners.

    Weights and values are float32, blended in the reference's order.

    :attr:`params` holds the layout's values (float32, the stored layout of the table: the
    kernel's, or the grid's) as one Dr.Jit array, what the plugin exposes to ``mi.traverse``
    as its differentiable parameter ``values``. Lookups read packed f16 codes (the kernel's fast
    path) until the values are edited (:meth:`edit`) or need gradients, and :attr:`params`
    from then on.
    """

    def __init__(self, layout):
        import drjit as dr
        import mitsuba as mi

        version = layout.get("version")
        if version != LAYOUT_VERSION:
            raise brdftab.Error(
                f"device layout version {version!r}: this plugin implements version "
                f"{LAYOUT_VERSION} (brdftab and brdftab.mitsuba from different releases?)")
        self.kind = layout.get("kind")
        if self.kind not in ("kernel", "grid"):
            raise brdftab.Error(f"device layout kind {self.kind!r} is not supported by the JIT path")
        self.c = int(layout["channels"])
        self.quantity = layout["quantity"]
        self.channel_names = layout["channel_names"]
        self.wavelengths = None
        if self.channel_names and self.channel_names[0].endswith("nm"):
            self.wavelengths = [float(x[:-2]) for x in self.channel_names]
        self.Float64 = dr.float64_array_t(mi.Float)
        self.UInt = mi.UInt32
        # The albedo calibration (src/table/calibration/mod.rs): per-channel factors k_in(θi)
        # and k_out(θo) on nodes uniform in t = sqrt(1 - cos θ), channels innermost.
        self.calibration = None
        cal = layout.get("calibration")
        if cal is not None:
            c = int(cal["channels"])
            f_in = np.asarray(cal["factors"], np.float32)
            f_out = cal.get("out_factors")
            f_out = None if f_out is None else mi.Float(np.asarray(f_out, np.float32))
            self.calibration = (mi.Float(f_in), f_out, c, f_in.size // c, float(cal["t_end"]))
        self.kernel = None
        k = layout.get("kernel")
        if k is not None:
            self.kernel = dict(k)
            self.kernel["axes"] = [
                (mi.Float(np.asarray(a["c"], np.float32)), mi.Float(np.asarray(a["d"], np.float32)),
                 len(a["c"]), int(a["nodes"]), float(a["cut"]))
                for a in k["axes"]]
            values = np.ascontiguousarray(k["values"], np.float32)
            self.kernel["values"] = mi.Float(values)
            self.params = self.kernel["values"]
            # The f16 codes of an adaptive table, four to a 64-bit word (module docs of
            # _packed_codes): one gather per corner node instead of one per channel.
            self.kernel["packed"] = _packed_codes(values, self.c)
            if self.kernel["packed"] is not None:
                self.kernel["values"] = None
            dr.eval()
        self.grid = None
        g = layout.get("grid")
        if g is not None:
            self.grid = dict(g)
            self.param, self.sym, self.interp = g["param"], g["symmetry"], g["interp"]
            if self.param not in ("inout", "halfdiff") or self.interp not in ("linear", "nearest"):
                raise brdftab.Error(f"device layout grid {self.param!r}, {self.interp!r} is not "
                                    "supported by the JIT path")
            self.axes = [dict(ax) for ax in g["axes"]]
            self.shape = [int(n) for n in g["shape"]]
            self.values = mi.Float(np.ascontiguousarray(g["values"], np.float32))
            dr.eval(self.values)
            if k is None:
                self.params = self.values
            for ax in self.axes:
                # Warped axes (adaptive grids): the knots as a Dr.Jit array, for gathers.
                if isinstance(ax["mapping"], dict) and "warp" in ax["mapping"]:
                    ax["_knots"] = self.Float64(
                        np.asarray(ax["mapping"]["warp"]["knots"], np.float64))
        if (self.kind == "kernel") != (self.kernel is not None) or (
                self.kernel is None and self.grid is None):
            raise brdftab.Error(f"device layout of kind {self.kind!r} without its arrays")
        #: Number of values in :attr:`params` (what an edit must keep).
        self.n_values = dr.width(self.params)
        if self.kernel is not None and self.grid is not None and dr.width(self.values) != self.n_values:
            raise brdftab.Error("device layout: a kernel's fallback grid holds other values than "
                                "the kernel")
        #: Whether :attr:`params` were edited (:meth:`edit`): lookups read them, not the codes.
        self.edited = False

    def edit(self):
        """Lookups read :attr:`params` from now on (after a change of them in place, as
        ``mi.SceneParameters.update`` makes): the kernel's float32 values instead of its packed
        codes, and a kernel's fallback grid (pairs beyond a resampled axis's cut) the same values,
        which it holds in the same order. Raises :class:`brdftab.Error` when the number of values
        changed."""
        import drjit as dr

        n = dr.width(self.params)
        if n != self.n_values:
            raise brdftab.Error(
                f"values: {n} given, the table holds {self.n_values} (an edit keeps the table's "
                "layout; bake another table for another grid)")
        self.edited = True

    def _reads_params(self):
        """Whether lookups read :attr:`params` (edited, or tracking gradients) rather than the
        layout's own arrays."""
        import drjit as dr

        return self.edited or dr.grad_enabled(self.params)

    # -- GridLayout: canonical coordinates (symmetry.rs) -------------------------------------
    def coords(self, wi, wo):
        """Canonical [x0, x1, x2, x3] (float64) and the validity mask, of a grid layout."""
        import drjit as dr

        if self.kind != "grid":
            # A kernel layout's lookup works in its own warped variables (`lookup`); it has no
            # canonical grid coordinates.
            raise brdftab.Error(
                f"coords: a {self.kind} layout has no canonical grid coordinates (grid layouts "
                "only; `lookup` evaluates every layout)"
            )

        F = self.Float64
        # Linear lookups use the polynomial acos/atan2 (canonical_coords_fast) on `unit`
        # vectors, nearest lookups the exact functions (canonical_coords) on normalized ones.
        fast = self.interp != "nearest"
        wi, ok_i = _unit([F(wi.x), F(wi.y), F(wi.z)], fast)
        wo, ok_o = _unit([F(wo.x), F(wo.y), F(wo.z)], fast)
        valid = ok_i & ok_o & (wi[2] > 0) & (wo[2] > 0)
        iso, rec, bil = self.sym["isotropic"], self.sym["reciprocal"], self.sym["bilateral"]
        tau = 2 * math.pi

        def acos(x):
            return _fast_acos(x) if fast else dr.acos(dr.clip(x, -1.0, 1.0))

        def atan2(y, x):
            return _fast_atan2(y, x) if fast else dr.atan2(y, x)

        if self.param == "inout":
            ti, to = acos(wi[2]), acos(wo[2])
            swap = ti > to
            if iso:
                dot = wi[0] * wo[0] + wi[1] * wo[1]
                cross = wi[0] * wo[1] - wi[1] * wo[0]
                d = atan2(cross, dot)
                if rec:  # θ1 ≤ θ2: (θi, θo, Δφ) → (θo, θi, −Δφ)
                    ti, to, d = dr.select(swap, to, ti), dr.select(swap, ti, to), dr.select(swap, -d, d)
                d = dr.abs(d) if bil else dr.select(d < 0, d + tau, d)
                return [ti, F(0.0), to, d], valid
            a1, a3 = atan2(wi[1], wi[0]), atan2(wo[1], wo[0])
            if rec:
                ti, to = dr.select(swap, to, ti), dr.select(swap, ti, to)
                a1, a3 = dr.select(swap, a3, a1), dr.select(swap, a1, a3)
            if bil:
                neg = a1 < 0
                a1, a3 = dr.select(neg, -a1, a1), dr.select(neg, -a3, a3)
            a1 = dr.select(a1 < 0, a1 + tau, a1)
            a3 = dr.select(a3 < 0, a3 + tau, a3)
            return [ti, a1, to, a3], valid
        if not fast:
            return self._half_diff_exact(wi, wo, valid)
        # halfdiff, as half_diff_angles_fast: unnormalized h = wi + wo
        h = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]]
        hxy2 = h[0] * h[0] + h[1] * h[1]
        hh = hxy2 + h[2] * h[2]
        valid &= hh > 1e-300
        length = dr.sqrt(dr.maximum(hh, 1e-300))
        inv = 1.0 / length
        th = acos(h[2] * inv)
        td = acos((wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) * inv)
        y = (wi[1] * h[0] - wi[0] * h[1]) * length
        x = (wi[0] * h[0] + wi[1] * h[1]) * h[2] - wi[2] * hxy2
        pole = ~(hxy2 > 1e-24 * hh)
        pd = dr.select(pole, atan2(wi[1], wi[0]), atan2(y, x))
        return self._fold_half_diff(th, atan2(h[1], h[0]), td, pd), valid

    def _half_diff_exact(self, wi, wo, valid):
        """geometry::half_diff_vectors: h normalized, d = wi rotated by −φh about z, −θh
        about y; exact acos/atan2."""
        import drjit as dr

        h = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]]
        n2 = h[0] * h[0] + h[1] * h[1] + h[2] * h[2]
        valid &= n2 > 0
        inv = 1.0 / dr.sqrt(dr.maximum(n2, 1e-300))
        h = [h[0] * inv, h[1] * inv, h[2] * inv]
        th = dr.acos(dr.clip(h[2], -1.0, 1.0))
        ph = dr.atan2(h[1], h[0])
        sp, cp = dr.sin(-ph), dr.cos(-ph)
        x1, y1, z1 = cp * wi[0] - sp * wi[1], sp * wi[0] + cp * wi[1], wi[2]
        st, ct = dr.sin(-th), dr.cos(-th)
        dx, dy, dz = ct * x1 + st * z1, y1, -st * x1 + ct * z1
        td = dr.acos(dr.clip(dz, -1.0, 1.0))
        pd = dr.atan2(dy, dx)
        return self._fold_half_diff(th, ph, td, pd), valid

    def _fold_half_diff(self, th, ph, td, pd):
        """symmetry.rs fold_half_diff."""
        import drjit as dr

        iso, rec, bil = self.sym["isotropic"], self.sym["reciprocal"], self.sym["bilateral"]
        pi, tau = math.pi, 2 * math.pi
        if iso:
            ph = self.Float64(0.0)
        else:
            if bil:
                neg = ph < 0
                ph, pd = dr.select(neg, -ph, ph), dr.select(neg, -pd, pd)
            ph = dr.select(ph < 0, ph + tau, ph)
        iso_bil = iso and bil
        if rec and iso_bil:
            a = dr.abs(pd)
            pd = dr.minimum(a, pi - a)
        elif rec:
            pd = dr.select(pd < 0, pd + pi, pd)
        elif iso_bil:
            pd = dr.abs(pd)
        else:
            pd = dr.select(pd < 0, pd + tau, pd)
        return [th, ph, td, pd]

    # -- GridLayout: stored axes (table/grid/axis.rs, StoredAxis) -------------------------------
    @staticmethod
    def _cell_coordinate(ax, x, exact):
        import drjit as dr

        n = float(ax["size"])
        lo, hi = ax["lo"], ax["hi"]
        r = (x - lo) / (hi - lo) if exact else (x - lo) * (1.0 / (hi - lo))
        if ax["periodic"]:
            return r * n
        m, nodes = ax["mapping"], ax["nodes"]
        if isinstance(m, dict):
            u = JitTable._warp(ax, m["warp"], x, hi)
            return u * n - 0.5 if nodes == "centers" else u * (n - 1.0)
        if m == "sqrt" and nodes == "cell_start":
            return dr.sqrt(dr.maximum(r * n * n, 0.0))
        if m == "uniform" and nodes == "cell_start":
            return r * n
        if m == "uniform":
            u = r
        elif m == "sqrt":
            u = dr.sqrt(dr.maximum(r, 0.0))
        elif m == "cos":  # θ axes, lo = 0
            u = (math.cos(lo) - dr.cos(x)) / (math.cos(lo) - math.cos(hi))
        else:
            raise brdftab.Error(f"axis mapping {m!r} is not supported by the JIT path")
        if nodes == "centers":
            return u * n - 0.5
        if nodes == "edges":
            return u * (n - 1.0)
        return u * n

    @staticmethod
    def _warp(ax, w, x, hi):
        """u of angle x on a warped axis (``warp.rs``: Warp::u_of_angle)."""
        import drjit as dr

        Fx = type(x)
        var = w["var"]
        if var == "sqrt_sine":
            v = dr.sqrt(dr.maximum(dr.sin(x), 0.0))
        elif var == "quarter_power":
            v = dr.sqrt(math.sqrt(2.0) * dr.abs(dr.sin(0.5 * x)))
        elif var == "half_power":
            v = math.sqrt(2.0) * dr.abs(dr.sin(0.5 * x))
        elif var == "pseudo_angle":
            def pseudo(sn, cs):
                d = abs(cs) + abs(sn)
                return 0.5 - 0.5 * cs / d if d > 0 else 0.0
            sn, cs = dr.sin(x), dr.cos(x)
            d = dr.abs(cs) + dr.abs(sn)
            p = dr.select(d > 0, 0.5 - 0.5 * cs / dr.maximum(d, 1e-300), 0.0)
            v = p / pseudo(math.sin(hi), math.cos(hi))
        else:
            raise brdftab.Error(f"warp variable {var!r} is not supported by the JIT path")
        k = float(len(w["knots"]) - 1)
        t = dr.clip(v * k, 0.0, k)
        j = dr.minimum(dr.floor(t), k - 1.0)
        ju = dr.uint32_array_t(Fx)(j)
        a = dr.gather(Fx, ax["_knots"], ju)
        b = dr.gather(Fx, ax["_knots"], ju + 1)
        return a + (t - j) * (b - a)

    def _continuous(self, ax, x):
        s = self._cell_coordinate(ax, x, False)
        return s - 0.5 if ax["nodes"] == "cell_start" else s

    def _linear(self, ax, x):
        """(i0, i1, t) as StoredAxis::linear."""
        import drjit as dr

        U, Fl = self.UInt, type(self.values)
        n = ax["size"]
        if n <= 1:
            return U(0), U(0), Fl(0.0)
        s = self._continuous(ax, x)
        if ax["periodic"]:
            fin = dr.isfinite(s)
            s = dr.select(fin, s, 0.0)
            fi = dr.floor(s)
            t = Fl(s - fi)
            i0 = fi - n * dr.floor(fi / n)  # rem_euclid
            i0 = U(dr.clip(i0, 0, n - 1))
            i1 = dr.select(i0 + 1 == n, U(0), i0 + 1)
            return i0, i1, t
        s = dr.select(s > 0, dr.minimum(s, n - 1.0), 0.0)
        i0 = dr.minimum(U(dr.floor(s)), n - 2)
        return i0, i0 + 1, Fl(s - self.Float64(i0))

    def _nearest(self, ax, x):
        import drjit as dr

        n = ax["size"]
        if n <= 1:
            return self.UInt(0)
        if ax["nodes"] == "cell_start":
            i = dr.floor(self._cell_coordinate(ax, x, True))
        else:
            i = dr.floor(self._continuous(ax, x) + 0.5)
        if ax["periodic"]:
            i = dr.select(dr.isfinite(i), i, 0.0)
            i = i - n * dr.floor(i / n)
            return self.UInt(dr.clip(i, 0, n - 1))
        i = dr.select(i > 0, dr.minimum(i, n - 1.0), 0.0)
        return self.UInt(i)

    # -- DeviceLayout::eval --------------------------------------------------------------------
    def lookup(self, wi, wo, active=True):
        """f_r per channel: a list of c float32 arrays (0 where invalid)."""
        import drjit as dr

        if self.kernel is None:
            return self._grid_lookup(wi, wo, active)
        out, inside, valid = self._kernel_lookup(wi, wo, active)
        if self.grid is not None:  # resampled axes: pairs beyond a cut take the grid
            g = self._grid_lookup(wi, wo, active & ~inside)
            out = [dr.select(inside, a, b) for a, b in zip(out, g)]
            return [dr.select(valid, x, 0.0) for x in out]
        return [dr.select(valid & inside, x, 0.0) for x in out]

    def _grid_lookup(self, wi, wo, active):
        """GridLayout::eval, then the quantity's projection in float64 (kernel/project.rs
        ``project_out``)."""
        import drjit as dr

        x, valid = self.coords(wi, wo)
        valid &= active
        n0, s1, n2, s3 = self.shape
        c = self.c
        values = self.params if self._reads_params() else self.values
        Fl = type(values)
        if self.interp == "nearest":
            idx = [self._nearest(self.axes[k], x[k]) for k in range(4)]
            base = (((idx[0] * s1 + idx[1]) * n2 + idx[2]) * s3 + idx[3]) * c
            out = [dr.gather(Fl, values, base + k, valid) for k in range(c)]
        else:
            lin = [self._linear(self.axes[k], x[k]) for k in range(4)]
            out = [Fl(0.0) for _ in range(c)]
            corners1 = [(lin[1][0], 1.0 - lin[1][2])]
            if s1 > 1:
                corners1.append((lin[1][1], lin[1][2]))
            for a, wa in ((lin[0][0], 1.0 - lin[0][2]), (lin[0][1], lin[0][2])):
                for p, wp in corners1:
                    for b, wb in ((lin[2][0], 1.0 - lin[2][2]), (lin[2][1], lin[2][2])):
                        w2 = wa * wp * wb
                        row = ((a * s1 + p) * n2 + b) * s3
                        for q, wq in ((lin[3][0], 1.0 - lin[3][2]), (lin[3][1], lin[3][2])):
                            wt = w2 * wq
                            base = (row + q) * c
                            for k in range(c):
                                out[k] = out[k] + wt * dr.gather(Fl, values, base + k, valid)
        if self.quantity != "fr" or self.calibration is not None:
            out = self._project(wi, wo, out)
        return [dr.select(valid, o, 0.0) for o in out]

    def _project(self, wi, wo, out):
        """f_r from an interpolated quantity (kernel/project.rs, ``project_out``): other than f_r,
        divided by cos θo or cos θi cos θo of the unit directions (at least 1e-30) in float64,
        clamped at 0; then the calibration."""
        import drjit as dr

        F64 = self.Float64
        iz = _unit([F64(wi.x), F64(wi.y), F64(wi.z)], False)[0][2]
        oz = _unit([F64(wo.x), F64(wo.y), F64(wo.z)], False)[0][2]
        if self.quantity != "fr":
            f = oz if self.quantity == "fr_cos_out" else iz * oz
            s = 1.0 / dr.maximum(f, 1e-30)
            out = [dr.maximum(type(o)(F64(o) * s), 0.0) for o in out]
        Fl = type(out[0])
        return self._calibrate(Fl(iz), Fl(oz), out)

    def _calibrate(self, iz, oz, out):
        """Times the calibration's k_in(θi) k_out(θo) (``Calibration::apply`` in
        src/table/calibration/mod.rs): on each, t = sqrt(1 - cos θ) in float32, s = min(t (n - 1)/t_end, n - 1), linear between
        nodes ⌊s⌋ and the next."""
        import drjit as dr

        if self.calibration is None:
            return out
        f_in, f_out, c, n, t_end = self.calibration
        Fl = type(out[0])
        scale = float(np.float32(n - 1) / np.float32(t_end))

        def blend(fac, cos, out):
            t = dr.sqrt(dr.maximum(1.0 - Fl(cos), 0.0))
            s = dr.minimum(t * scale, float(n - 1))
            j = dr.minimum(self.UInt(dr.trunc(s)), n - 2)
            f = s - Fl(j)
            res = []
            for k, o in enumerate(out):
                a = dr.gather(Fl, fac, j * c + k)
                b = dr.gather(Fl, fac, (j + 1) * c + k)
                res.append(o * (a + f * (b - a)))
            return res

        out = blend(f_in, iz, out)
        if f_out is not None:
            out = blend(f_out, oz, out)
        return out

    # -- KernelLayout --------------------------------------------------------------------------
    def _kernel_lookup(self, wi, wo, active):
        """KernelLayout::vars and ::blend, then the projection in float32 (kernel/project.rs
        ``project_f32``). Returns (values, inside every cut, valid)."""
        import drjit as dr
        import mitsuba as mi

        F64, U = self.Float64, self.UInt
        reads_params = self._reads_params()
        kv = self.params if reads_params else self.kernel["values"]
        Fl = mi.Float
        (ix, iy, iz), ok_i = _unit([F64(wi.x), F64(wi.y), F64(wi.z)], True)
        (ox, oy, oz), ok_o = _unit([F64(wo.x), F64(wo.y), F64(wo.z)], True)
        ix, iy, iz, ox, oy, oz = (Fl(x) for x in (ix, iy, iz, ox, oy, oz))
        valid = ok_i & ok_o & (iz > 0) & (oz > 0) & active
        hx, hy, hz = ix + ox, iy + oy, iz + oz
        r2 = hx * hx + hy * hy
        hh = r2 + hz * hz
        hl = dr.sqrt(hh)
        if self.kernel["h_var"] == "quarter_power":
            vh = dr.sqrt(dr.sqrt(r2 / (hh + hl * hz)))
        else:
            vh = dr.sqrt(dr.sqrt(r2 / hh))
        ex, ey, ez = ix - ox, iy - oy, iz - oz
        e2 = ex * ex + ey * ey + ez * ez
        vd = dr.sqrt(e2 / (2.0 * (2.0 + hl)))
        dx = hz * (hx * ix + hy * iy) - r2 * iz
        dy = dr.abs(hl * (hx * iy - hy * ix))
        den = dr.abs(dx) + dy
        safe = dr.select(den > 0, den, 1.0)
        if self.kernel["quarter"]:
            vp = dr.select(den > 0, dy / safe, 0.0)
        else:
            vp = dr.select(den > 0, 0.5 - 0.5 * (dx / safe), 0.0)
        inside = dr.full(dr.mask_t(Fl), True, dr.width(vh))
        nodes = []
        for (c_, d_, k, n, cut), v in zip(self.kernel["axes"], (vh, vd, vp)):
            inside &= v < cut
            t = v * float(k)
            ju = dr.minimum(U(dr.trunc(dr.minimum(t, k - 0.5))), k - 1)
            sv = dr.gather(Fl, c_, ju) + t * dr.gather(Fl, d_, ju)
            sv = dr.minimum(dr.maximum(sv, 0.0), n - 1.0)
            i = dr.minimum(dr.trunc(dr.minimum(sv, n - 1.5)), float(n - 2))
            nodes.append((U(i), sv - i))
        (ih, th), (id_, td), (ip, tp) = nodes
        c = self.c
        nodes_row = self.kernel["axes"][2][3]
        nodes_chunk = self.kernel["axes"][1][3] * nodes_row
        node = ih * nodes_chunk + id_ * nodes_row + ip
        oh, od, op = 1.0 - th, 1.0 - td, 1.0 - tp
        rows = [(node, oh * od), (node + nodes_row, oh * td), (node + nodes_chunk, th * od),
                (node + nodes_chunk + nodes_row, th * td)]
        out = [Fl(0.0) for _ in range(c)]
        ok = valid & inside
        packed = None if reads_params else self.kernel["packed"]
        if packed is not None:
            words, scale = packed
            W = type(words)

            # A subnormal code's bits moved into a float32 are a float32 subnormal, which the
            # LLVM backend flushes to 0 as an input: such a code is its mantissa times 2^-24
            # instead (times the same power of two; exact), chosen by its exponent bits.
            sub_scale = scale * 2.0**-136

            def value(h):
                normal = dr.reinterpret_array(Fl, ((h & 0x7FFF) << 13) | ((h & 0x8000) << 16))
                sub = Fl(h & 0x3FF) * sub_scale
                sub = dr.select((h & 0x8000) != 0, -sub, sub)
                return dr.select((h & 0x7C00) == 0, sub, normal * scale)

            def corner(n):
                q = dr.gather(W, words, n, ok)
                lo, hi = U(q & 0xFFFFFFFF), U(q >> 32)
                codes = [lo & 0xFFFF, lo >> 16, hi & 0xFFFF, hi >> 16][:c]
                return [value(h) for h in codes]
        else:
            def corner(n):
                return [dr.gather(Fl, kv, n * c + ch, ok) for ch in range(c)]
        for r, w in rows:
            w0, w1 = w * op, w * tp
            x0, x1 = corner(r), corner(r + 1)
            for ch in range(c):
                out[ch] = out[ch] + (w0 * x0[ch] + w1 * x1[ch])
        if self.quantity != "fr":
            cc = oz if self.quantity == "fr_cos_out" else iz * oz
            inv = 1.0 / dr.maximum(cc, 1e-30)
            out = [dr.maximum(x * inv, 0.0) for x in out]
        out = self._calibrate(iz, oz, out)
        return out, inside, valid


def _spectrum_is_its_rgb(brdf):
    """Whether `brdf` at any wavelength is its RGB read through the RGB basis
    (:func:`brdftab.rgb_basis`): RGB sources, and models linear in their one coloured parameter
    (an RGB k_d, k_s or Schlick F0). Checked on 16 fixed pairs at 10 wavelengths, to float32
    rounding; a spectrum that is not the basis mix of its RGB (n, k data, an RGB index of
    refraction, two coloured factors) differs there by far more."""
    if list(brdf.channels) != ["R", "G", "B"]:
        return False
    t = np.radians(np.array([5.0, 20.0, 35.0, 50.0, 65.0, 80.0, 30.0, 60.0]))
    p = np.radians(np.array([0.0, 40.0, 100.0, 170.0, 220.0, 300.0, 130.0, 250.0]))
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], 1)
    wi = np.concatenate([d, d[::-1]])
    wo = np.concatenate([np.roll(d, 1, axis=0), d * np.array([-1.0, -1.0, 1.0])])
    nm = np.array([380.0, 420.0, 460.0, 500.0, 540.0, 580.0, 620.0, 660.0, 700.0, 760.0])
    f = brdf.eval(wi, wo).astype(np.float64)
    s = brdf.eval_spectral(wi, wo, nm).astype(np.float64)
    mix = f @ brdftab.rgb_basis(nm).T
    return bool(np.allclose(s, mix, rtol=1e-5, atol=1e-6 * max(1.0, float(mix.max()))))


class JitBrdftabBSDF(_Common):
    """JIT variants: a table evaluated in Dr.Jit, tabulated importance sampling."""

    def __init__(self, props):
        import drjit as dr
        import mitsuba as mi

        self._base.__init__(self, props)
        self._init_common(props)
        if self.brdf.flags["lobes"]["delta"]:
            raise brdftab.Error(
                f"{self.source}: a delta lobe (a mirror or refractor, alone or in a sum) has no "
                "table; the JIT variants of the plugin do not support it (use a scalar variant)"
            )
        # The cache of baked tables: property `cache` (default true), `cache_dir` (default
        # $BRDFTAB_CACHE_DIR, $XDG_CACHE_HOME/brdftab or ~/.cache/brdftab).
        self.cache = _bool_prop(props, "cache", True)
        self.cache_dir = _cache_dir_prop(props)
        options = {}
        for key in ("preset", "grid"):
            v = _prop(props, key)
            if v is not None:
                options[key] = str(v)
        # A spectral variant bakes a spectral source (a spectral RGL file, a model whose
        # spectrum is not its RGB through the basis: a metal's n, k, an RGB refractive index) at
        # 21 wavelengths; any other source stays an RGB table, read at each wavelength through
        # the RGB basis in `_f` — exact, where sampling the basis every 20 nm would move a
        # saturated colour by ~1 %.
        kind = brdftab_kind(self.source)
        if self.spectral and kind in ("spec", "rgl") and not _spectrum_is_its_rgb(self.brdf):
            options.setdefault("wavelengths", list(range(380, 781, 20)))
        # The table as the library describes it for devices (`device_layout`): the JIT lookup
        # implements that layout, not the grid's description. An opened table moves its values
        # into the layout (`Brdf.device_layout`, for the interpolation it was opened with); a
        # table baked in memory goes through `Table.device_layout` (`auto`: nearest on MERL
        # cells, linear otherwise).
        layout = self._table(options)
        self.table = JitTable(layout)
        # An RGB table in a spectral variant: the RGB basis, uploaded once (see `_f`).
        self._basis = None
        if self.spectral and self.table.wavelengths is None:
            b = brdftab.rgb_basis(_BASIS_NM)
            self._basis = [mi.Float(np.ascontiguousarray(b[:, k])) for k in range(3)]
        # The library's importance sampler (conditional half-vector warps of f_r cos θo given
        # wi), on the densities it exports for the table (or the source): brdftab._halfwarp.
        # (A kernel layout is of an isotropic table.)
        # The library's resolution (SamplingResolution::for_source): 64 × 64 half-vector nodes
        # (128 θh for a peak too sharp for 64) and 32 θi nodes, 48 for a table read by cell (its
        # values step as the view moves), half again the θi and φh nodes for a lobe that changes
        # shape between grazing views (the Phong family); 48 × 48 and 20 × 16 anisotropic.
        # `sampling_res` overrides the half-vector nodes.
        self._nearest = layout["kind"] == "grid" and layout["grid"]["interp"] == "nearest"
        self._sampling_res = _sampling_res_prop(props)
        self.sampler = self._sampler_of(self._sampled)
        dr.eval()

    def _sampler_of(self, brdf):
        """The library's sampler of ``brdf`` (a Brdf over the table or its source) at the
        library's resolution, or at the ``sampling_res`` property's half-vector nodes."""
        res = brdf.sampling_resolution(adjoint=True, nearest=self._nearest)
        if self._sampling_res is not None:
            res["theta_h"] = res["phi_h"] = int(self._sampling_res)
        return HalfVectorSampler(brdf.sampling_nodes(adjoint=True, **res))

    def _layout(self, table):
        """The device layout of ``table``: a Brdf over a table (its values move into the
        layout, for the interpolation it was opened with: ``auto`` resolved) or a
        ``brdftab.Table`` (``auto``: the library's default for its grid)."""
        if hasattr(table, "values"):
            return table.device_layout(self.interp)
        return table.device_layout()

    def _table(self, options):
        """The device layout of the table the plugin evaluates (see ``__init__``)."""
        # What the sampling distributions are built from: the table when it is at hand as a
        # Brdf, else the source.
        self._sampled = self.brdf
        # The table the layout is of (a Brdf over a stored table, or a brdftab.Table baked in
        # memory), for export_table.
        self._table_src = self.brdf
        if brdftab_kind(self.source) == "table" and not options:
            return self._layout(self.brdf)
        # MERL files keep their own cells, RGL files get the library's adaptive grid. Other
        # sources: given a preset or grid, that; else an isotropic bilateral source (every
        # isotropic model) the smallest adaptive grid within MODEL_TARGET_ERROR, calibrated to
        # its albedo, and any other source the library's default bake (the medium preset,
        # calibrated where the preset misses the albedo: brdftab.bake's default).
        if brdftab_kind(self.source) not in ("merl", "rgl"):
            flags = self.brdf.flags
            if "preset" in options or "grid" in options:
                options.setdefault("preset", "medium")
            elif flags["isotropic"] and flags["bilateral"]:
                options.setdefault("target_error", MODEL_TARGET_ERROR)
        if options.get("preset") and options.get("grid"):
            options.pop("preset")
        if self.cache:
            # The baked table from the cache of baked tables (brdftab.bake_cached), lossless
            # (f32: the values an in-memory bake gives), so a scene loads a material's table
            # from disk after its first bake.
            options = {"param": "halfdiff", "codec": "f32", **options}
            if self.cache_dir is not None:
                # A directory that cannot be made is the property's error (the cache's own
                # said "/proc/x: No such file or directory (os error 2)", naming no property).
                try:
                    os.makedirs(self.cache_dir, exist_ok=True)
                except OSError as e:
                    raise brdftab.Error(
                        f"brdftab plugin: `cache_dir` {self.cache_dir!r}: cannot be made a "
                        f"directory ({e.strerror or e})"
                    ) from e
            for refresh in (False, True):
                hit = brdftab.bake_cached(self.source, self.cache_dir, refresh, **options)
                try:
                    t = brdftab.open(hit["path"], interp=self.interp)
                    self._sampled = self._table_src = t
                    return self._layout(t)
                except brdftab.Error:
                    if refresh:  # a fresh bake that does not open is the library's error
                        raise
        b = self.brdf
        if "wavelengths" in options:
            b = brdftab.open(self.source, interp=self.interp, wavelengths=options.pop("wavelengths"))
        self._table_src = b.table(param="halfdiff", **options)
        return self._layout(self._table_src)

    def _f(self, wi, wo, lam, active):
        """f_r of the table at (wi, wo) as the variant's spectrum; ``lam``: the wavelengths of
        a spectral variant (``si.wavelengths``), else None."""
        import drjit as dr
        import mitsuba as mi

        f = self.table.lookup(wi, wo, active)
        if not self.spectral:
            return self._unpolarized([f[0], f[1], f[2]])
        wl = self.table.wavelengths
        if wl is None:
            # An RGB table in a spectral variant: the library's reading of RGB channels at a
            # wavelength (`Brdf.eval_spectral`, `Channels::mix_at`: the colour-preserving basis
            # `brdftab.rgb_basis`, tabulated at 1 nm and interpolated as the library does), as
            # the scalar variants give it.
            out = []
            for i in range(len(lam)):
                u = dr.clip(lam[i] - float(_BASIS_NM[0]), 0.0, float(len(_BASIS_NM) - 1))
                j = dr.minimum(mi.UInt32(u), len(_BASIS_NM) - 2)
                t = u - mi.Float(j)
                v = 0
                for k in range(3):
                    w = dr.lerp(dr.gather(mi.Float, self._basis[k], j),
                                dr.gather(mi.Float, self._basis[k], j + 1), t)
                    v = v + w * f[k]
                out.append(v)
            return mi.UnpolarizedSpectrum(out)
        out = []
        for i in range(len(lam)):
            x = lam[i]
            v = dr.select(x <= wl[0], f[0], f[-1])
            for k in range(len(wl) - 1):
                t = (x - wl[k]) / (wl[k + 1] - wl[k])
                v = dr.select((x > wl[k]) & (x <= wl[k + 1]), dr.lerp(f[k], f[k + 1], t), v)
            out.append(v)
        return mi.UnpolarizedSpectrum(out)

    def _when(self, active, si, args, on, off):
        """``on(*args, lam)`` where ``active``, ``off(*args, lam)`` elsewhere (``lam``: the
        spectral variant's wavelengths, else None), as a symbolic branch. Dr.Jit's LLVM backend
        then skips the table for packets of lanes none of which needs it — rays that missed the
        object, other materials, finished paths — where a masked evaluation computes every lane
        (a table lookup costs about as much as the rest of a path; BENCHMARKS.md)."""
        import drjit as dr

        if self.spectral:
            return dr.if_stmt(args=(*args, si.wavelengths), cond=active, true_fn=on,
                              false_fn=off, label="brdftab")
        return dr.if_stmt(args=tuple(args), cond=active, true_fn=lambda *a: on(*a, None),
                          false_fn=lambda *a: off(*a, None), label="brdftab")

    def _value(self, wi, wo, lam, active, adjoint=False):
        """f_r cos θo (0 where not ``active``); ``adjoint``: f_r(wo, wi) cos θo (importance
        transport). Unpolarized: :meth:`_spectrum` makes it the variant's Spectrum."""
        import drjit as dr

        f = self._f(wo, wi, lam, active) if adjoint else self._f(wi, wo, lam, active)
        return dr.select(active, f * _normalize(wo).z, 0.0)

    def eval(self, ctx, si, wo, active=True):
        """f_r · cos θ(wo) from the table (0 below either horizon)."""
        import mitsuba as mi

        active = mi.Bool(active) & (si.wi.z > 0) & (wo.z > 0) & _finite(si.wi) & _finite(wo)
        if self.delta or not self._enabled(ctx, True):
            return mi.Spectrum(0.0)
        adjoint = self._adjoint(ctx)
        # Unpolarized inside the branch, the variant's Spectrum outside: a Mueller matrix
        # returned from a symbolic branch made Dr.Jit's LLVM backend emit invalid IR
        # ("Instruction does not dominate all uses") in llvm_ad_spectral_polarized.
        return self._spectrum(self._when(
            active, si, (si.wi, wo, active),
            lambda wi, wo, a, lam: self._value(wi, wo, lam, a, adjoint),
            lambda wi, wo, a, lam: mi.UnpolarizedSpectrum(0.0)))

    def _pdf(self, wi, wo, active):
        import drjit as dr

        return self.sampler.pdf(_normalize(wi), _normalize(wo), active)

    def pdf(self, ctx, si, wo, active=True):
        """The density of :meth:`sample` drawing wo given ``si.wi``."""
        import mitsuba as mi

        active = mi.Bool(active) & (si.wi.z > 0) & (wo.z > 0) & _finite(si.wi) & _finite(wo)
        if self.delta or not self._enabled(ctx, True):
            return mi.Float(0.0)
        return self._when(active, si, (si.wi, wo, active),
                          lambda wi, wo, a, lam: self._pdf(wi, wo, a),
                          lambda wi, wo, a, lam: mi.Float(0.0))

    def eval_pdf(self, ctx, si, wo, active=True):
        """``(eval(...), pdf(...))`` in one table lookup."""
        import mitsuba as mi

        active = mi.Bool(active) & (si.wi.z > 0) & (wo.z > 0) & _finite(si.wi) & _finite(wo)
        if self.delta or not self._enabled(ctx, True):
            return mi.Spectrum(0.0), mi.Float(0.0)
        adjoint = self._adjoint(ctx)
        value, pdf = self._when(active, si, (si.wi, wo, active),
                                lambda wi, wo, a, lam: (self._value(wi, wo, lam, a, adjoint),
                                                        self._pdf(wi, wo, a)),
                                lambda wi, wo, a, lam: (mi.UnpolarizedSpectrum(0.0),
                                                        mi.Float(0.0)))
        return self._spectrum(value), pdf

    def sample(self, ctx, si, sample1, sample2, active=True):
        """A ``BSDFSample3f`` and its weight f_r · cos θ(wo) / pdf, drawn by the library's
        sampler (conditional half-vector warps, :mod:`brdftab._halfwarp`)."""
        import drjit as dr
        import mitsuba as mi

        active = mi.Bool(active) & (si.wi.z > 0) & _finite(si.wi)
        if not self._enabled(ctx, False):
            return dr.zeros(mi.BSDFSample3f), mi.Spectrum(0.0)
        adjoint = self._adjoint(ctx)

        def on(wi, u, a, lam):
            wo, pdf = self.sampler.sample(_normalize(wi), u, a)
            ok = a & (wo.z > 0) & (pdf > 0)
            value = self._value(wi, wo, lam, ok, adjoint)
            return wo, pdf, dr.select(ok, value / dr.maximum(pdf, 1e-20), 0.0)

        def off(wi, u, a, lam):
            return mi.Vector3f(0.0), mi.Float(0.0), mi.UnpolarizedSpectrum(0.0)

        wo, pdf, weight = self._when(active, si, (si.wi, sample2, active), on, off)
        weight = self._spectrum(weight)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = wo
        bs.pdf = pdf
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+self.m_flags & ~int(mi.BSDFFlags.FrontSide))
        bs.sampled_component = mi.UInt32(0)
        return bs, weight

    def traverse(self, callback):
        """Exposes ``values``: the table's values as lookups read them (float32, the table's
        stored layout and quantity, before its albedo calibration — lookups keep applying it),
        differentiable: ``eval``, ``eval_pdf`` and ``sample``'s weight are linear in them."""
        import mitsuba as mi

        callback.put("values", self.table.params, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys):
        """After ``values`` changed: lookups read them (:meth:`JitTable.edit`). The sampling
        distributions stay those of the table as loaded: draws and their pdf stay consistent
        and weights follow the new values (``eval / pdf``), so renders stay unbiased;
        :meth:`resample` rebuilds them for a table edited far from its start."""
        if not keys or "values" in keys:
            self.table.edit()

    def resample(self):
        """Rebuilds the sampling distributions from the table's current ``values`` (between
        renders, after edits that moved the lobe: the loaded table's distributions stay
        consistent but no longer follow it). Costs what building them at a scene load costs
        (tens of ms for an RGL file's default table); the pdf is then the one a plugin loading
        the exported table would have."""
        import drjit as dr

        self.sampler = self._sampler_of(self.export_table().open(self.interp))
        dr.eval()

    def export_table(self):
        """The table this plugin evaluates with its current ``values`` (after an optimization,
        the optimized ones) as a :class:`brdftab.Table` on the same grid, albedo calibration
        included; save it with :meth:`brdftab.Table.save`. Values as lookups read them: an
        adaptive table's f16-rounded values, an f_r table's unmeasured (negative) ones as 0."""
        import drjit as dr

        src = self._table_src
        table = src if isinstance(src, brdftab.Table) else src.table()
        values = np.asarray(dr.detach(self.table.params), np.float32)
        if values.size != table.values.size:
            raise brdftab.Error(
                f"{self.source}: the device layout holds {values.size} values, the table stores "
                f"{table.values.size} (a packed inout table's layout expands them); export is "
                "for layouts that hold the stored values")
        return table.with_values(values)
