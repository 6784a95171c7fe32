"""Mitsuba 3's own `measured` plugin loads .bsdf files written by `brdftab convert` and agrees
with their sources (issue 15).

Metric: relative RMSE of f_r weighted by cos θi cos θo over random pairs with both directions
within 80° of the normal, i.e. sqrt(Σ((m − f cos θo) cos θi)² / Σ(f cos θo cos θi)²) where m is
Mitsuba's `eval` (f_r·cos θo, si.wi = brdftab's wi = the tensor's incident axis) and f is
`brdftab eval SOURCE`. Bars: 2% for models and a MERL file; a re-encoded RGL file must evaluate
in Mitsuba as its original does.

Needs `mitsuba` and `numpy` (pip) and a built CLI: target/release/brdftab, or $BRDFTAB_BIN.
"""

import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

from conftest import unavailable

try:
    import mitsuba as mi
except ImportError:
    unavailable("mitsuba is not installed (pip install mitsuba)")
mi.set_variant("scalar_rgb")

ROOT = pathlib.Path(__file__).resolve().parents[3]
BIN = os.environ.get("BRDFTAB_BIN", str(ROOT / "target" / "release" / "brdftab"))
PAIRS = 3000
MAX_THETA = math.radians(80.0)

CT_GOLD = '{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}'
GGX_COPPER = (
    '{"model": "sum", "terms": [{"model": "lambert", "kd": [0.12, 0.06, 0.04]}, '
    '{"model": "ggx", "alpha": 0.2, "fresnel": {"conductor": "Cu"}}]}'
)

# The MERL file is written from a diffuse + specular model: MERL's nearest-cell lookup itself
# differs from a sharp lobe by ~2% (MERL from CT m = 0.3 gold vs the model: 2.25%), which no
# resampling of the MERL file can undo, so that source would measure the MERL grid, not the writer.
MERL_MODEL = (
    '{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, '
    '{"model": "cook_torrance", "m": 0.4, "ks": 0.5}]}'
)


def rgl_dir():
    """The shipped RGL files: data/rgl in the repository, else ../shared/data/measured/rgl."""
    for d in (ROOT / "data" / "rgl", ROOT.parent / "shared" / "data" / "measured" / "rgl"):
        if d.is_dir() and any(d.glob("*.bsdf")):
            return d
    raise FileNotFoundError("no RGL data: neither data/rgl nor ../shared/data/measured/rgl exists")


def run(*args, stdin=None):
    r = subprocess.run([BIN, *args], input=stdin, capture_output=True, text=True)
    assert r.returncode == 0, f"brdftab {' '.join(args)}: {r.stderr}"
    return r.stdout


def pairs(n, seed):
    rng = np.random.default_rng(seed)

    def cap(u, v):
        z = 1.0 - (1.0 - math.cos(MAX_THETA)) * u
        s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
        p = 2.0 * math.pi * v
        return np.stack([s * np.cos(p), s * np.sin(p), z], axis=1)

    return cap(rng.random(n), rng.random(n)), cap(rng.random(n), rng.random(n))


def brdftab_eval(source, wi, wo, wavelengths=None):
    lines = "\n".join(" ".join(f"{x:.17g}" for x in (*a, *b)) for a, b in zip(wi, wo))
    extra = ["--wavelengths", ",".join(str(w) for w in wavelengths)] if wavelengths else []
    out = run("eval", source, *extra, stdin=lines + "\n")
    return np.array([[float(x) for x in l.split()] for l in out.strip().splitlines()])


def mitsuba_eval(path, wi, wo, wavelengths=None):
    """Mitsuba's f_r·cos θo; RGB files in scalar_rgb, spectral ones in scalar_spectral at the
    given 4 wavelengths. `path` may also be a plugin's dict."""
    mi.set_variant("scalar_spectral" if wavelengths else "scalar_rgb")
    try:
        d = path if isinstance(path, dict) else {"type": "measured", "filename": str(path)}
        bsdf = mi.load_dict(d)
        ctx = mi.BSDFContext()
        si = mi.SurfaceInteraction3f()
        if wavelengths:
            si.wavelengths = mi.Spectrum(wavelengths)
        c = len(wavelengths) if wavelengths else 3
        out = np.zeros((len(wi), c))
        for k, (a, b) in enumerate(zip(wi, wo)):
            si.wi = mi.Vector3f(*a)
            v = bsdf.eval(ctx, si, mi.Vector3f(*b))
            out[k] = [v[i] for i in range(c)]
        return out
    finally:
        mi.set_variant("scalar_rgb")


def error(path, source, seed=1, wavelengths=None):
    wi, wo = pairs(PAIRS, seed)
    f = brdftab_eval(source, wi, wo, wavelengths)
    assert f.shape == (PAIRS, len(wavelengths) if wavelengths else 3)
    m = mitsuba_eval(path, wi, wo, wavelengths)
    w = (wi[:, 2] * wo[:, 2])[:, None]
    ref = f * w
    return math.sqrt(np.sum((m * wi[:, 2][:, None] - ref) ** 2) / np.sum(ref**2))


def convert(source, out, *extra):
    run("convert", source, str(out), "--pairs", "0", *extra)
    return out


@pytest.mark.parametrize("name,spec", [("ct_gold", CT_GOLD), ("ggx_copper", GGX_COPPER)])
def test_models(tmp_path, name, spec):
    path = convert(spec, tmp_path / f"{name}.bsdf")
    e = error(path, spec)
    print(f"{name}: Mitsuba vs source {e:.4%}")
    assert e < 0.02


def test_an_anisotropic_file_keeps_its_axes(tmp_path):
    """An anisotropic source's file keeps its orientation in Mitsuba: `measured` on the file
    agrees with the source, and the source's α_x lies along Mitsuba's own u (the shading frame's
    first tangent), so `roughconductor` with (α_u, α_v) = (α_x, α_y) agrees too and the swapped
    one does not."""
    spec = '{"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.4}'
    path = convert(spec, tmp_path / "aniso.bsdf")
    e = error(path, spec)
    print(f"anisotropic GGX: Mitsuba vs source {e:.4%}")
    assert e < 0.02

    def rough(au, av):
        return {"type": "roughconductor", "distribution": "ggx", "alpha_u": au, "alpha_v": av,
                "material": "none", "specular_reflectance": {"type": "rgb", "value": 1.0}}

    same, swapped = error(rough(0.1, 0.4), spec), error(rough(0.4, 0.1), spec)
    print(f"roughconductor (0.1, 0.4): {same:.4%}, (0.4, 0.1): {swapped:.4%}")
    assert same < 0.02 and swapped > 0.5


def test_spectral_file_in_a_spectral_variant(tmp_path):
    """`--wavelengths` writes `spectra` + `wavelengths` (the only kind pbrt-v4 reads); Mitsuba
    evaluates it at wavelengths on the file's grid."""
    path = convert(
        GGX_COPPER, tmp_path / "cu_spectral.bsdf", "--wavelengths", "400,450,500,550,600,650,700"
    )
    e = error(path, GGX_COPPER, wavelengths=[450.0, 500.0, 550.0, 600.0])
    print(f"spectral GGX copper: Mitsuba vs source {e:.4%}")
    assert e < 0.02


def test_merl_written_from_a_model(tmp_path):
    merl = tmp_path / "model.binary"
    run("convert", MERL_MODEL, str(merl))
    path = convert(str(merl), tmp_path / "merl.bsdf")
    e = error(path, str(merl))
    print(f"MERL: Mitsuba vs source {e:.4%}")
    assert e < 0.02


@pytest.mark.parametrize("name", sorted(p.name for p in rgl_dir().glob("*.bsdf")))
def test_rgl_reencoded(tmp_path, name):
    """A re-encoded file is its original's table, so Mitsuba evaluates it as it evaluates the
    original. (Against `brdftab eval` of the original the bar would not hold for every file:
    Mitsuba's `measured` does not clip the interpolated values at 0 as brdftab's and the
    reference reader do, and cg_sunflower and vch_golden_yellow hold negative values, so
    Mitsuba on those *original* files differs from the readers by 1.9 % and 2.2 %.)"""
    src = rgl_dir() / name
    path = convert(str(src), tmp_path / name)
    wi, wo = pairs(PAIRS, 1)
    re, orig = mitsuba_eval(path, wi, wo), mitsuba_eval(src, wi, wo)
    w = wi[:, 2][:, None]
    e = math.sqrt(np.sum(((re - orig) * w) ** 2) / np.sum((orig * w) ** 2))
    print(f"{name}: Mitsuba, re-encoded vs original {e:.4%}")
    assert e < 1e-6


def test_mitsuba_agrees_with_brdftab_on_a_shipped_file():
    """The harness itself: Mitsuba on an original file vs brdftab's reader on it."""
    src = rgl_dir() / "paper_white_rgb.bsdf"
    assert error(src, str(src)) < 1e-4
