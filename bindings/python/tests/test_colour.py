"""Colour through a spectral renderer: an RGB source read at wavelengths (`brdftab.rgb_basis`,
`Brdf.eval_spectral`, the plugin's spectral variants) is a spectrum whose colour, projected as a
spectral renderer's film projects it, is the source's RGB.

The oracle is Mitsuba 3's own projection, `mi.spectrum_list_to_srgb(..., d65=True)` (its CIE
1931 tables, D65 and XYZ → sRGB matrix, its integration): an implementation independent of the
library's. Its projection of the flat spectrum 1 is 0.9989, not 1 (its tables and integration),
so results are divided by that white; what remains between the two implementations of the same
standard is the published matrix's four decimals (≤ 1.5e-4 a channel) and the two integration
grids (Mitsuba's 1000 points against 471): tolerance 5e-4 of the colour's largest channel.
"""

import math

import numpy as np
import pytest

import brdftab

from conftest import unavailable

try:
    import drjit as dr
    import mitsuba as mi
except ImportError:
    unavailable("mitsuba is not installed (pip install mitsuba)")

WL = np.arange(360.0, 831.0)
TOL = 5e-4


def mi_srgb(values):
    """Mitsuba's linear sRGB of the spectrum `values` at WL, relative to its white."""
    mi.set_variant("scalar_rgb")
    proj = lambda v: np.array(mi.spectrum_list_to_srgb(list(WL), [float(x) for x in v], False, True))
    return proj(values) / proj(np.ones_like(WL))


def dirn(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]


def test_rgb_basis_makes_spectra_of_the_primaries_colours():
    b = brdftab.rgb_basis(WL)
    assert b.shape == (WL.size, 3) and b.dtype == np.float64
    assert (b >= 0).all()
    np.testing.assert_allclose(b.sum(axis=1), 1.0, atol=1e-15)
    for k in range(3):
        np.testing.assert_allclose(mi_srgb(b[:, k]), np.eye(3)[k], atol=TOL)
    # any shape in, that shape + (3,) out; held at the ends outside 360-830 nm
    assert brdftab.rgb_basis(np.full((2, 5), 500.0)).shape == (2, 5, 3)
    # what is not a wavelength is refused, as eval_spectral and the C ABI refuse it
    for bad in [0.0, -5.0, np.nan, np.inf]:
        with pytest.raises(ValueError, match="not a wavelength"):
            brdftab.rgb_basis([500.0, bad])
    np.testing.assert_array_equal(brdftab.rgb_basis(200.0), b[0])
    np.testing.assert_array_equal(brdftab.rgb_basis([1e4]), b[-1:])


def test_an_rgb_file_at_wavelengths_renders_in_its_colour(rgl):
    src = brdftab.open(str(rgl / "cc_ibiza_sunset_rgb.bsdf"))  # saturated red-orange
    for wi, wo in ((dirn(45, 0), dirn(45, 180)), (dirn(20, 0), dirn(60, 120))):
        rgb = src.eval(wi, wo).astype(np.float64)
        spectrum = src.eval_spectral(wi, wo, WL)
        np.testing.assert_allclose(mi_srgb(spectrum), rgb, atol=TOL * rgb.max())


def scalar_spectral_eval(bsdf, wi, wo):
    """The plugin's eval in scalar_spectral at every wavelength of WL (four per query)."""
    out = []
    for i in range(0, WL.size, 4):
        lam = list(WL[i:i + 4]) + [WL[-1]] * (4 - len(WL[i:i + 4]))
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wo)
        si.wavelengths = mi.Spectrum(lam)
        out.extend(np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*wi)))[:4])
    return np.array(out[:WL.size])


def test_the_scalar_spectral_plugin_renders_an_rgb_source_in_its_colour(rgl):
    import brdftab.mitsuba

    path = str(rgl / "cc_ibiza_sunset_rgb.bsdf")
    wi, wo = dirn(45, 0), dirn(45, 180)
    mi.set_variant("scalar_rgb")
    brdftab.mitsuba.register()
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*wo)
    rgb = np.array(mi.load_dict({"type": "brdftab", "source": path}).eval(
        mi.BSDFContext(), si, mi.Vector3f(*wi)))
    mi.set_variant("scalar_spectral")
    brdftab.mitsuba.register()
    spectrum = scalar_spectral_eval(mi.load_dict({"type": "brdftab", "source": path}), wi, wo)
    np.testing.assert_allclose(mi_srgb(spectrum), rgb, atol=TOL * rgb.max())


@pytest.mark.parametrize("kind", ["table", "spec"])
def test_the_jit_spectral_plugin_reads_rgb_sources_in_their_colour(tmp_path, kind):
    """An RGB table, or a model whose spectrum is its RGB through the basis (one coloured
    factor: Schlick's F0), in llvm_ad_spectral — an RGB table read through the basis uploaded
    once, interpolated in Dr.Jit — has the colour the llvm_ad_rgb variant gives it. (The
    spectral variant baked such a model at 21 wavelengths 20 nm apart: ~1 % off.)"""
    import brdftab.mitsuba

    try:
        mi.set_variant("llvm_ad_rgb")
        dr.eval(mi.Float(1.0) + 1)
    except Exception:
        unavailable("llvm_ad_rgb needs libLLVM (apt-get install libllvm19; DRJIT_LIBLLVM_PATH)")
    spec = '{"model": "ggx", "alpha": 0.3, "fresnel": {"schlick": [0.9, 0.35, 0.05]}}'
    path = str(tmp_path / "orange.btdb")
    if kind == "table":
        brdftab.bake(spec, path, preset="small")
    else:
        path = spec
    wi, wo = dirn(30, 0), dirn(40, 180)
    # `preset` chooses how a model is baked; a table is read as stored (given both, an error)
    opts = {} if kind == "table" else {"preset": "small"}
    brdftab.mitsuba.register()
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.wi = mi.Vector3f(*wo)
    rgb = np.array(mi.load_dict({"type": "brdftab", "source": path, **opts,
                                 "cache_dir": str(tmp_path / "cache")}).eval(
        mi.BSDFContext(), si, mi.Vector3f(*wi))).ravel()
    mi.set_variant("llvm_ad_spectral")
    brdftab.mitsuba.register()
    b = mi.load_dict({"type": "brdftab", "source": path, **opts,
                      "cache_dir": str(tmp_path / "cache")})
    lanes = -(-WL.size // 4)
    lam = np.concatenate([WL, np.full(4 * lanes - WL.size, WL[-1])]).reshape(lanes, 4)
    si = dr.zeros(mi.SurfaceInteraction3f, lanes)
    si.wi = mi.Vector3f(*np.tile(wo, (lanes, 1)).T)
    si.wavelengths = mi.Spectrum(*lam.T)
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(*np.tile(wi, (lanes, 1)).T)))
    spectrum = v.T.ravel()[:WL.size]
    # float32 lookups and basis: 1e-6 relative on top of the projections' TOL
    np.testing.assert_allclose(mi_srgb(spectrum), rgb, atol=TOL * rgb.max() + 1e-6)
