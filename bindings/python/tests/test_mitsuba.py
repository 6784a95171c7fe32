"""The Mitsuba 3 plugin `brdftab` against Mitsuba's own `measured` plugin on the same RGL file,
its Dr.Jit table lookup against the Rust lookup, and its sampler through `mitsuba.chi2`."""

import json
import math
import os
import pathlib
import shutil

import numpy as np
import pytest

import brdftab

from conftest import unavailable

try:
    import drjit as dr
    import mitsuba as mi
except ImportError:
    unavailable("mitsuba is not installed (pip install mitsuba)")

RGL_FILE = "vch_golden_yellow_rgb.bsdf"  # glossy vinyl: the hard case for eval and sampling


def have_llvm():
    try:
        mi.set_variant("llvm_ad_rgb")
        dr.eval(mi.Float(1.0) + 1)
        return True
    except Exception:
        return False


def use(variant):
    if variant.startswith("llvm") and not have_llvm():
        unavailable("llvm_ad_rgb needs libLLVM (apt-get install libllvm19; DRJIT_LIBLLVM_PATH)")
    mi.set_variant(variant)
    import brdftab.mitsuba

    brdftab.mitsuba.register()


def random_dirs(n, seed, min_cos=0.1):
    rng = np.random.default_rng(seed)
    t = np.arccos(rng.uniform(min_cos, 1, n))
    p = rng.uniform(0, 2 * math.pi, n)
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], 1)


def eval_both(variant, ours, ref, wi, wo):
    ctx = mi.BSDFContext()
    if variant.startswith("scalar"):
        a, b = [], []
        for x, y in zip(wi, wo):
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(*x)
            v = mi.Vector3f(*y)
            a.append(np.array(ours.eval(ctx, si, v)))
            b.append(np.array(ref.eval(ctx, si, v)))
        return np.array(a), np.maximum(np.array(b), 0)
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(*wi.T)
    v = mi.Vector3f(*wo.T)
    # `measured` interpolates RGB to slightly negative values near sharp peaks; brdftab clips
    # at 0 (as the RGL reference reader does)
    return np.array(ours.eval(ctx, si, v)).T, np.maximum(np.array(ref.eval(ctx, si, v)).T, 0)


def test_scalar_eval_matches_measured(rgl):
    use("scalar_rgb")
    f = str(rgl / RGL_FILE)
    ours = mi.load_dict({"type": "brdftab", "source": f})
    ref = mi.load_dict({"type": "measured", "filename": f})
    wi, wo = random_dirs(300, 1), random_dirs(300, 2)
    a, b = eval_both("scalar_rgb", ours, ref, wi, wo)
    rel = np.abs(a - b) / np.maximum(np.abs(b), 1e-3 * np.abs(b).max())
    assert rel.max() <= 1e-3, rel.max()
    # eval = f_r cos θo with si.wi = brdftab's wi
    f_r = brdftab.open(f).eval(wi, wo)
    np.testing.assert_allclose(a, f_r * wo[:, 2:3], rtol=1e-5, atol=1e-7)


def test_scalar_sample_pdf_consistent(rgl):
    use("scalar_rgb")
    ours = mi.load_dict({"type": "brdftab", "source": str(rgl / RGL_FILE)})
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.3, 0.1, 0.9)
    rng = np.random.default_rng(0)
    for _ in range(50):
        bs, w = ours.sample(ctx, si, float(rng.random()), mi.Point2f(*rng.random(2)))
        if bs.pdf > 0:
            np.testing.assert_allclose(bs.pdf, ours.pdf(ctx, si, bs.wo), rtol=1e-5)
            np.testing.assert_allclose(np.array(w), np.array(ours.eval(ctx, si, bs.wo)) / bs.pdf,
                                       rtol=1e-4)


def test_scalar_spectral_and_errors():
    use("scalar_spectral")
    b = mi.load_dict({"type": "brdftab", "source": '{"model": "lambert", "kd": 0.5}'})
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0, 0, 1)
    si.wavelengths = mi.Spectrum([450, 500, 550, 600])
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1)))
    np.testing.assert_allclose(v, 0.5, rtol=1e-6)
    use("scalar_rgb")
    with pytest.raises(Exception, match="no-such-file"):
        mi.load_dict({"type": "brdftab", "source": "/nonexistent/no-such-file.bsdf"})
    with pytest.raises(Exception, match="unknown variant"):
        mi.load_dict({"type": "brdftab", "source": '{"model": "nope"}'})
    with pytest.raises(Exception, match="source"):
        mi.load_dict({"type": "brdftab"})


# ---- llvm_ad_rgb -----------------------------------------------------------------------------

CASES = [
    ('{"model": "ggx", "alpha": 0.3}', dict(preset="small")),
    ('{"model": "ggx", "alpha": 0.3}', dict(grid="merl")),
    ('{"model": "ggx", "alpha": 0.3}', dict(grid="16x1x16x32", param="inout", symmetry="isotropic")),
    ('{"model": "ggx", "alpha": 0.3}', dict(grid="16x1x16x32", param="inout",
                                            symmetry="isotropic,bilateral")),
    ('{"model": "ward", "alpha_x": 0.2, "alpha_y": 0.4, "ks": 0.5}', dict(preset="small")),
    ('{"model": "ward", "alpha_x": 0.2, "alpha_y": 0.4, "ks": 0.5}', dict(preset="small",
                                                                          symmetry="none")),
    ('{"model": "ward", "alpha_x": 0.2, "alpha_y": 0.4, "ks": 0.5}',
     dict(grid="16x16x16x16", param="inout", symmetry="bilateral")),
    ("RGL", dict(preset="small")),
    ("RGL", dict()),  # the default: an adaptive grid with warped axes
    # packed inout reciprocity (unpacked by the device layout)
    ('{"model": "ggx", "alpha": 0.3}', dict(grid="16x1x16x32", param="inout",
                                            symmetry="isotropic,reciprocal,bilateral")),
    # MERL-style fixed mappings on a small grid: the kernel's resampled axes, the grid beyond
    ('{"model": "ggx", "alpha": 0.3}', dict(grid="16x1x16x32", param="halfdiff")),
    # adaptive tables of models, calibrated with one symmetric factor: f_r (the plugin's
    # default for GGX) and f_r cos θi cos θo (Cook-Torrance, unbounded at the horizon)
    ('{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}', dict(target_error=0.004)),
    ('{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}',
     dict(target_error=0.01)),
]


@pytest.mark.parametrize("interp", ["linear", "nearest"])
@pytest.mark.parametrize("case", range(len(CASES)))
def test_jit_lookup_matches_rust(case, interp, tmp_path, rgl):
    use("llvm_ad_rgb")
    from brdftab.mitsuba import JitTable

    src, opts = CASES[case]
    if src == "RGL":
        src = str(rgl / RGL_FILE)
    out = str(tmp_path / "t.btdb")
    brdftab.bake(src, out, **opts)
    b = brdftab.open(out, interp=interp)
    layout = b.table().device_layout(interp)
    moved = b.device_layout()  # the opened table's own layout: the same arrays
    for part in ("kernel", "grid"):
        if layout[part] is not None:
            np.testing.assert_array_equal(layout[part]["values"], moved[part]["values"])
    jt = JitTable(layout)
    rng = np.random.default_rng(case)
    wi, wo = rng.normal(size=(20000, 3)), rng.normal(size=(20000, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]) + 1e-3, np.abs(wo[:, 2]) + 1e-3
    wo[:5000] = wi[:5000] * [-1, -1, 1] + rng.normal(size=(5000, 3)) * 1e-3  # near specular
    wi[::97, 2] = -0.5  # some below the horizon
    # Mitsuba's directions are float32: the Rust lookup gets the same rounded directions
    wi, wo = wi.astype(np.float32).astype(np.float64), wo.astype(np.float32).astype(np.float64)
    want = b.eval(wi, wo)
    got = np.stack([np.array(x) for x in jt.lookup(mi.Vector3f(*wi.T), mi.Vector3f(*wo.T))], -1)
    rel = np.abs(got - want) / np.maximum(np.abs(want), 1e-6 * np.abs(want).max())
    print(f"case {case} {layout['kind']} {interp}: max rel {rel.max():.2e}, "
          f"exact {np.mean(got == want):.4f}")
    # The contract is 1e-5 (a device may round differently); the LLVM backend does the same
    # IEEE operations as DeviceLayout::eval, so nearly every pair is bit-equal (measured: all).
    assert np.mean(got == want) >= 0.999, np.mean(got == want)
    if interp == "linear":
        assert rel.max() <= 1e-5, rel.max()
    else:
        # a nearest lookup exactly on a cell boundary may round to the other cell
        assert np.mean(rel > 1e-6) < 1e-4, rel.max()
    assert np.all(got[::97] == 0)


def test_jit_tables_of_isotropic_models_are_adaptive_and_calibrated(tmp_path):
    """The JIT variants bake an isotropic model to MODEL_TARGET_ERROR (calibrated: its albedo
    pinned with one symmetric factor), an anisotropic one as the library's default bake does
    (Ward: the medium preset, calibrated — uncalibrated it is 4-5 % off in albedo at 89°), and
    the medium preset when asked; the plugin's lookups are the library's table of that
    request."""
    use("llvm_ad_rgb")
    from brdftab.mitsuba import MODEL_TARGET_ERROR

    wi, wo = random_dirs(4000, 11, 0.02), random_dirs(4000, 12, 0.02)
    wi, wo = wi.astype(np.float32).astype(np.float64), wo.astype(np.float32).astype(np.float64)
    ggx = '{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}'
    ward = '{"model": "ward", "alpha_x": 0.2, "alpha_y": 0.4, "ks": 0.5}'
    # (source, the plugin's properties, the library bake that makes the same table, calibrated)
    for src, props, opts, calibrated in (
            (ggx, {}, dict(target_error=MODEL_TARGET_ERROR), True),
            (ward, {}, dict(), True),
            (ward, dict(preset="medium"), dict(preset="medium"), False)):
        d = mi.load_dict({"type": "brdftab", "source": src, "cache_dir": str(tmp_path), **props})
        assert (d.table.calibration is not None) == calibrated
        out = str(tmp_path / "t.btdb")
        brdftab.bake(src, out, codec="f32", **opts)
        t = brdftab.open(out)
        want = t.eval(wi, wo)
        got = np.stack([np.array(x) for x in d.table.lookup(mi.Vector3f(*wi.T),
                                                            mi.Vector3f(*wo.T))], -1)
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6 * np.abs(want).max())
        # f_r is reciprocal through the calibration too
        back = np.stack([np.array(x) for x in d.table.lookup(mi.Vector3f(*wo.T),
                                                             mi.Vector3f(*wi.T))], -1)
        np.testing.assert_allclose(back, got, rtol=1e-5, atol=1e-6 * np.abs(want).max())
        if src == ggx:  # a small table: 288 k values against the medium preset's 4.4 M
            assert t.table().values.size < 1_000_000
            # its f16 codes read four to a word (the bit-equal lookups above)
            assert d.table.kernel["packed"] is not None


def test_jit_table_refuses_unknown_layouts():
    use("llvm_ad_rgb")
    from brdftab.mitsuba import JitTable

    layout = brdftab.open('{"model": "lambert", "kd": 0.5}').table(grid="4x1x4x8").device_layout()
    assert layout["version"] == 1 and layout["kind"] in ("kernel", "grid")
    with pytest.raises(brdftab.Error, match="not a table"):
        brdftab.open('{"model": "lambert", "kd": 0.5}').device_layout()
    for bad in ({"version": 2}, {"kind": "octree"}):
        with pytest.raises(brdftab.Error):
            JitTable({**layout, **bad})


@pytest.mark.parametrize("preset", ["medium", None])  # None: the default, an adaptive grid
def test_jit_eval_matches_measured_within_table_error(rgl, tmp_path, preset):
    use("llvm_ad_rgb")
    f = str(rgl / RGL_FILE)
    opts = {} if preset is None else {"preset": preset}
    ours = mi.load_dict({"type": "brdftab", "source": f, **opts})
    ref = mi.load_dict({"type": "measured", "filename": f})
    wi, wo = random_dirs(5000, 3, 0.2), random_dirs(5000, 4, 0.2)
    a, b = eval_both("llvm_ad_rgb", ours, ref, wi, wo)
    # the table's own error: Rust table lookup vs the native RGL evaluation, same pairs
    out = str(tmp_path / "m.btdb")
    brdftab.bake(f, out, **opts)
    native = brdftab.open(f).eval(wi, wo) * wo[:, 2:3]
    table = brdftab.open(out).eval(wi, wo) * wo[:, 2:3]
    scale = np.abs(b).max()
    err_plugin = np.sqrt(np.mean((a - b) ** 2)) / scale
    err_table = np.sqrt(np.mean((table - native) ** 2)) / scale
    err_native = np.sqrt(np.mean((native - b) ** 2)) / scale
    print(f"rel RMSE: plugin vs measured {err_plugin:.2e}, table vs native {err_table:.2e}, "
          f"native vs measured {err_native:.2e}")
    assert err_plugin <= 1.05 * (err_table + err_native) + 1e-6


# Views stop at 80°: beyond it mitsuba.chi2 refuses Mitsuba's own roughconductor and
# roughplastic (their pdf's cell integrals read 1.13–1.25 at 89–89.999°, BENCHMARKS session 42);
# the plugin's grazing draws are checked against the library's pdf instead
# (test_jit_pdf_near_the_horizon_is_the_librarys).
CHI2 = [
    ("RGL", {"preset": "small"}, [0.4, 0.1, 0.91]),
    # The default (adaptive) table, view within 2° of the normal: the pdf's cell integrals at
    # 8×8 points sum to 1.0062 (the peak at the normal is narrower than a cell), at 32×32 to
    # 1.00008 — the former rejected one draw sequence in four (p = 0.002).
    ("RGL", {}, [0.02, 0.0, 1.0], 32),
    # 80°: a peak narrower than the chi2 cells near the horizon; the cells' integral of the pdf
    # needs 32×32 points (at 8×8 it is off by 4 % in the two peak cells: p = 3e-6).
    ("RGL", {}, [0.985, 0.0, 0.17], 32),
    ('{"model": "ggx", "alpha": 0.4}', {"preset": "small"}, [0.0, 0.5, 0.866]),
    ('{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}', {}, [0.3, 0.2, 0.93]),
    # anisotropic: conditioned on θi and φi (four conditioning corners)
    ('{"model": "ward", "alpha_x": 0.1, "alpha_y": 0.3, "ks": 0.5}', {"preset": "small"},
     [0.5, 0.3, 0.81]),
    # a MERL file: the table of its cells read by cell, its sampler on 48 θi views
    ("MERL", {}, [0.6, 0.1, 0.79]),
    # a Phong lobe at a grazing view: the library gives it finer views (48 θi × 64 × 96 nodes),
    # the plugin's nodes follow; the lobe is narrower than the chi2 cells there (32×32 points)
    ('{"model": "reciprocal_phong", "ks": 0.5, "n": 200}', {}, [0.99, 0.0, 0.14], 32),
]


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "llvm_ad_spectral"])
def test_jit_calls_honour_the_active_mask(rgl, variant):
    """eval, pdf, eval_pdf and sample run the table inside a symbolic branch on ``active``
    (skipped for packets with no active lane): active lanes get what an all-active call gives,
    the others zeros — in blocks, as coherent lanes come, and lane by lane."""
    use(variant)
    d = mi.load_dict({"type": "brdftab", "source": str(rgl / RGL_FILE)})
    n = 4096
    wi, wo = random_dirs(n, 7, 0.1), random_dirs(n, 8, 0.1)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*wi.T)
    if variant.endswith("spectral"):
        si.wavelengths = mi.Spectrum(450.0, 520.0, 600.0, 680.0)
    v = mi.Vector3f(*wo.T)
    u = mi.Point2f(*np.random.default_rng(9).random((2, n)))
    ctx = mi.BSDFContext()
    full_e = np.array(d.eval(ctx, si, v))
    full_p = np.array(d.pdf(ctx, si, v))
    full_bs, full_w = d.sample(ctx, si, 0.5, u)
    full_wo, full_w = np.array(full_bs.wo), np.array(full_w)
    assert np.count_nonzero(full_p) > n // 2 and np.count_nonzero(full_e) > n // 2
    lanes = np.arange(n)
    for keep in ((lanes // 512) % 2 == 0, lanes % 3 == 0):
        m = mi.Bool(keep)
        e = np.array(d.eval(ctx, si, v, m))
        p = np.array(d.pdf(ctx, si, v, m))
        e2, p2 = d.eval_pdf(ctx, si, v, m)
        bs, w = d.sample(ctx, si, 0.5, u, m)
        for got, full in ((e, full_e), (np.array(e2), full_e), (np.array(w), full_w)):
            assert np.array_equal(got[..., keep], full[..., keep])
            assert not np.any(got[..., ~keep])
        for got in (p, np.array(p2)):
            assert np.array_equal(got[keep], full_p[keep]) and not np.any(got[~keep])
        assert np.array_equal(np.array(bs.wo)[:, keep], full_wo[:, keep])
        assert not np.any(np.array(bs.pdf)[~keep])


def test_jit_alias_draw_is_the_piecewise_bilinear_density(rgl):
    """The plugin's draw (the library's alias tables, ``brdftab._alias2d``) has the density of
    Mitsuba's ``MarginalContinuous2D1`` on the same nodes — an independent implementation of
    the piecewise-bilinear warp — and its draws follow that density (a 2D histogram)."""
    use("llvm_ad_rgb")
    import mitsuba as mi
    from brdftab._alias2d import AliasWarp2D

    nodes = brdftab.open(str(rgl / RGL_FILE)).sampling_nodes(adjoint=True)
    nt, ny, nx = nodes["nt"], nodes["ny"], nodes["nx"]
    data = np.asarray(nodes["data"], np.float32).reshape(nt, ny, nx)
    ref = mi.MarginalContinuous2D1(data, [np.linspace(0.0, 1.0, nt).tolist()], normalize=True)
    warp = AliasWarp2D(nodes["alias"], nx, ny)
    rng = np.random.default_rng(4)
    n = 200_000
    for t in (0.0, 0.0247, 0.5, 0.93, 1.0):
        st = t * (nt - 1)
        t0 = min(int(st), nt - 2)
        ft = st - t0
        corners = [(mi.UInt32(t0), mi.Float(1.0 - ft)), (mi.UInt32(t0 + 1), mi.Float(ft))]
        u = mi.Point2f(rng.random(n), rng.random(n))
        a = np.array(warp.eval(u, corners, True))
        b = np.array(ref.eval(u, [mi.Float(t)], True))
        # Both f32 sums of the same bilinear terms (normalized in f64 by the library, in f32 by
        # Mitsuba): a few f32 roundings apart.
        assert np.all(np.abs(a - b) <= 1e-5 * b + 1e-7 * b.max()), t
        p, pdf = warp.sample(u, corners, True)
        at = np.array(warp.eval(p, corners, True))
        # The draw's density against the density at the drawn point rounded to f32: that
        # rounding moves p by up to 2^-24 per axis, where the bilinear density's slope is at
        # most its largest value times the cells per axis.
        moved = 2 * 2.0**-24 * max(nx, ny) * at.max()
        assert np.all(np.abs(np.array(pdf) - at) <= 1e-4 * at + moved), t
        # Drawn points against the density's cell integrals (16 × 16 cells, 8 × 8 points
        # each): chi-square over cells expecting at least 5 points.
        h, _, _ = np.histogram2d(np.array(p.x), np.array(p.y), bins=16, range=[[0, 1], [0, 1]])
        g = (np.arange(128) + 0.5) / 128
        x, y = np.meshgrid(g, g, indexing="ij")
        ev = np.array(warp.eval(mi.Point2f(x.ravel(), y.ravel()), corners, True))
        e = ev.reshape(16, 8, 16, 8).mean(axis=(1, 3)) / 256 * n
        keep = e >= 5
        chi = float((((h - e) ** 2) / e)[keep].sum())
        dof = int(keep.sum()) - 1
        # p > 1e-4: chi² below dof + 4.3 √(2 dof) (normal approximation, dof in the hundreds).
        assert chi < dof + 4.3 * math.sqrt(2 * dof), (t, chi, dof)


def _sph(theta, phi):
    return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi),
                     math.cos(theta)])


#: Views a hair above the horizon: 89.9°, 89.999° and 1e-6 rad (elevations in radians).
GRAZING = [math.radians(0.1), math.radians(0.001), 1e-6]

#: How far a float32 direction drawn by the plugin lies from the exact draw: rounding
#: (≤ √3 2⁻²⁵ ≈ 5.2e-8) and ``dr.normalize`` (measured ≤ 1.0e-7 from unit length): 2⁻²².
DRAW_ROUNDING = 2.0**-22


def _envelope(lib, wo, wi, r):
    """The library's pdf(wo | wi) (Mitsuba's roles: brdftab's pdf(wi=wo, wo=wi)) and how far
    it moves when wo moves by r on the sphere: √2 × the largest change along two tangents of
    wo (a directional derivative is at most √2 × the larger of two orthogonal ones; the
    density is smooth on that scale)."""
    centre = lib.pdf(wo, wi)
    t1 = np.cross(wo, [0.0, 0.0, 1.0])
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    t2 = np.cross(wo, t1)
    moved = [lib.pdf(wo + s * r * t, wi) for t in (t1, t2) for s in (1, -1)]
    spread = math.sqrt(2) * np.max([np.abs(m - centre) for m in moved], axis=0)
    return centre, spread


def test_jit_pdf_near_the_horizon_is_the_librarys(tmp_path):
    """At views 0.1°, 0.001° and 1e-6 rad above the horizon, the plugin's pdf of directions
    near the mirror direction (|wi + wo| = 1e-3 … 1e-2, half vectors turned nearly 90° from
    wi's azimuth) is the library's at the same float32 directions, and the pdf ``sample``
    reports is the library's at the direction it hands back.

    The plugin read wi·h as ``dot(wi, h)`` in float32, whose terms are ~0.1 where its value is
    |wi + wo|/2 ~ 1e-3: off by up to 76 % at 89.9° and by 100 % (0 included) or 145× at
    89.999°. It now reads |ŵi + ŵo|/2, the sum taken in float64 from the directions made unit
    there (`_halfwarp._sums`). What float32 leaves: the half vector rounded (≤ 2⁻²³ rad, and as
    much from the frame's rotation) and the density's own float32 arithmetic, 1e-5 as the
    device contract; the node densities' slope is at most their largest value times the nodes
    per axis over the square (`test_jit_alias_draw_is_the_piecewise_bilinear_density`), and
    a tilt of 2⁻²² rad moves the square's coordinates by at most 2⁻²²/(π/2 · sin θh) ≤ 2⁻¹⁸
    at θh ≥ 0.05 in this test."""
    use("llvm_ad_rgb")
    out = str(tmp_path / "ggx.btdb")
    brdftab.bake('{"model": "ggx", "alpha": 0.1}', out, preset="small")
    lib = brdftab.open(out)
    d = mi.load_dict({"type": "brdftab", "source": out})
    wis, wos = [], []
    for delta in GRAZING:
        wi = _sph(math.pi / 2 - delta, 0.3)
        for th in (0.05, 0.2):
            for l in (1e-3, 3e-3, 1e-2):
                # wi·h = cos θh sin δ + sin θh cos δ cos Δφ = l/2.
                c = (l / 2 - math.cos(th) * math.sin(delta)) / (math.sin(th) * math.cos(delta))
                for sign in (1, -1):
                    h = _sph(th, 0.3 + sign * math.acos(c))
                    wo = 2 * wi.dot(h) * h - wi
                    wo[2] = abs(wo[2])  # folded at the horizon: the same density
                    wis.append(wi)
                    wos.append(wo)
    wi = np.array(wis).astype(np.float32).astype(np.float64)
    wo = np.array(wos).astype(np.float32).astype(np.float64)
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(*wi.T)
    got = np.array(d.pdf(mi.BSDFContext(), si, mi.Vector3f(*wo.T)))
    want = lib.pdf(wo, wi)
    nodes = lib.sampling_nodes(adjoint=True, **lib.sampling_resolution(adjoint=True))
    step = max(int(nodes["nx"]), int(nodes["ny"]))
    # The largest node density is bounded by the density here times the ratio of the
    # largest to this one; the slope term uses this point's density (the bilinear patch's
    # values within a cell differ by at most that patch's values).
    moved = 2.0**-18 * step * want
    bad = np.abs(got - want) > 1e-5 * want + moved
    assert not bad.any(), list(zip(got[bad], want[bad]))

    # sample: the pdf of each draw whose |wi + wo| ≥ 1e-3 (either preimage) against the
    # library's at the direction handed back, within the library's own change over the
    # rounding of that direction (DRAW_ROUNDING, tangent to it).
    n = 100_000
    rng = np.random.default_rng(2)
    for delta in GRAZING:
        wi = _sph(math.pi / 2 - delta, 0.3).astype(np.float32)
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(*[np.full(n, x, np.float32) for x in wi])
        u = mi.Point2f(*rng.random((2, n)).astype(np.float32))
        bs, _ = d.sample(mi.BSDFContext(), si, 0.5, u)
        p, wo = np.array(bs.pdf), np.array(bs.wo).T.astype(np.float64)
        w = np.broadcast_to(wi.astype(np.float64), wo.shape)
        near = np.minimum(np.linalg.norm(w + wo, axis=1),
                          np.linalg.norm(w + wo * [1, 1, -1], axis=1))
        keep = (p > 0) & (near >= 1e-3)
        assert keep.sum() > n // 2
        want, spread = _envelope(lib, wo[keep], w[keep], DRAW_ROUNDING)
        bad = np.abs(p[keep] - want) > spread + 1e-5 * want + 2.0**-18 * step * want
        assert not bad.any(), (delta, bad.sum(), p[keep][bad][:5], want[bad][:5])


@pytest.mark.parametrize("case", range(len(CHI2)))
def test_jit_chi2_sampling(rgl, case, tmp_path):
    """The plugin's sample and pdf agree (mitsuba.chi2) for isotropic and anisotropic tables,
    near the normal and at 80°, for a MERL file's cells and for a lobe with finer views."""
    use("llvm_ad_rgb")
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    src, opts, wi, *ires = CHI2[case]
    if src == "RGL":
        src = str(rgl / RGL_FILE)
    if src == "MERL":
        src = str(tmp_path / "ct.binary")
        brdftab.convert('{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}',
                        src)
        opts = {"cache_dir": str(tmp_path)}
    wi = [float(x) for x in np.asarray(wi) / np.linalg.norm(wi)]
    d = {"type": "brdftab", "source": src, **opts}

    def drawn(sample, *args):
        # BSDFAdapter's sample function, but counting every direction drawn with a density:
        # it drops draws whose weight is 0, and the sampler's floor puts some where f_r is 0
        # (the reciprocal Phong's lobe ends at 90° from the mirror direction) — unbiased, yet
        # the histogram would then miss mass the pdf has.
        import drjit as dr
        import mitsuba as mi

        bsdf = mi.load_dict(d)
        si = dr.zeros(mi.SurfaceInteraction3f, dr.width(sample))
        si.wi = wi
        bs, _ = bsdf.sample(mi.BSDFContext(), si, sample[0], mi.Vector2f(sample[1], sample[2]))
        return bs.wo, dr.select(bs.pdf > 0, 1.0, 0.0)

    chi2 = ChiSquareTest(
        domain=SphericalDomain(),
        sample_func=drawn,
        pdf_func=BSDFAdapter("brdftab", d, wi=wi)[1],
        sample_dim=3,
        res=101,
        ires=ires[0] if ires else 8,
    )
    assert chi2.run(), chi2.messages


def test_jit_render_matches_measured(rgl):
    use("llvm_ad_rgb")
    f = str(rgl / RGL_FILE)

    def scene(bsdf):
        return mi.load_dict({
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 3},
            "sensor": {"type": "perspective", "fov": 30,
                       "to_world": mi.ScalarTransform4f().look_at([0, -4, 2.5], [0, 0, 0], [0, 0, 1]),
                       "film": {"type": "hdrfilm", "width": 48, "height": 48},
                       "sampler": {"type": "independent", "sample_count": 32}},
            "sphere": {"type": "sphere", "bsdf": bsdf},
            "light": {"type": "point", "position": [2, -3, 4], "intensity": {"type": "rgb", "value": 60}},
            "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.2}},
        })

    ours = np.array(mi.render(scene({"type": "brdftab", "source": f}), seed=1))
    ref = np.array(mi.render(scene({"type": "measured", "filename": f}), seed=2))
    assert np.isfinite(ours).all()
    rel = abs(ours.mean() - ref.mean()) / ref.mean()
    assert rel < 0.03, rel


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_a_merl_file_is_read_by_cell_as_every_host_reads_it(tmp_path, variant):
    """The plugin's default interpolation is the library's (`auto`): a MERL file, and the table
    of its cells the JIT variants upload, is looked up by cell — the reader's values — not
    blended across cells (with `linear` they differ from the file by ~5 % here), and the JIT
    sampler conditions on the library's 48 views for tables read by cell."""
    use(variant)
    merl = str(tmp_path / "ct.binary")
    brdftab.convert('{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, '
                    '{"model": "cook_torrance", "m": 0.3}]}', merl)
    props = {} if variant.startswith("scalar") else {"cache_dir": str(tmp_path)}
    ours = mi.load_dict({"type": "brdftab", "source": merl, **props})
    wi, wo = random_dirs(300 if variant.startswith("scalar") else 4000, 5, 0.2), random_dirs(
        300 if variant.startswith("scalar") else 4000, 6, 0.2)
    reader = brdftab.open(merl).eval(wi, wo) * wo[:, 2:3]
    a, _ = eval_both(variant, ours, ours, wi, wo)
    rel = np.abs(a - reader) / np.maximum(np.abs(reader), 1e-3 * np.abs(reader).max())
    # by cell on both sides: equal but for pairs within rounding of a cell boundary
    assert np.mean(rel > 1e-4) < 1e-3, (np.mean(rel > 1e-4), rel.max())
    if not variant.startswith("scalar"):
        assert ours.table.kind == "grid" and ours.table.interp == "nearest"
        assert ours.sampler.nt == 48


# The scenes issue 22 measured the plugin's default tables in, against `measured` on the same
# file (bench/fidelity.py holds them and the rest of the table): the sphere under a constant
# environment and lit from the side (the terminator's bright bands, +2.6 % and +2.7 % then), the
# plane lit 10° above the horizon (paper_white +11 %), the view along the normal (cc_ibiza 0.150
# against 0.180, vch_golden_yellow 0.262 against 0.282). Each within the issue's bar for what it
# integrates (fidelity.SCENES: the albedo's 1 %, 1 % within 80°, the grazing band's 3 %), in
# every channel the file holds no negative values in (`measured` renders those, brdftab clips
# them as the reference reader does).
ISSUE_22_SCENES = {
    "paper_white_rgb.bsdf": ["sphere_env", "sphere_terminator", "plane_light10_view45"],
    "vch_golden_yellow_rgb.bsdf": ["sphere_env", "sphere_terminator", "normal_view_env"],
    "cc_ibiza_sunset_rgb.bsdf": ["normal_view_env"],
}


@pytest.mark.parametrize("name", sorted(ISSUE_22_SCENES))
def test_jit_renders_the_issue_22_scenes_as_measured_does(rgl, name):
    use("llvm_ad_rgb")
    import sys

    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "bench"))
    import fidelity

    scenes = [s for s in fidelity.SCENES if s[0] in ISSUE_22_SCENES[name]]
    assert len(scenes) == len(ISSUE_22_SCENES[name])
    rows = fidelity.compare(mi, rgl / name, scenes, spp_scale=0.25)
    compared = [x for r in rows for x in r["rel"] if x is not None]
    assert len(compared) >= 2 * len(rows), rows  # at least two channels per scene
    bad = [(r["scene"], r["rel"], r["bar"]) for r in rows if not r["ok"]]
    assert not bad, bad


def test_scalar_nan_and_infinite_directions_give_zero():
    # The NaN rule of every host: f_r = 0, pdf = 0, no sample. eval multiplied the library's 0
    # by cos θo computed from wo, which a NaN component of wo made NaN.
    use("scalar_rgb")
    ctx = mi.BSDFContext()
    for source in ['{"model": "ggx", "alpha": 0.3}', '{"model": "lambert", "kd": 0.3}']:
        b = mi.load_dict({"type": "brdftab", "source": source})
        good = (0.3, 0.1, 0.9)
        bad = [(math.nan, 0.0, 1.0), (0.0, math.nan, 1.0), (math.inf, 0.0, 1.0), (0.0, 0.0, 0.0)]
        for wi, wo in [(g, x) for x in bad for g in [good]] + [(x, good) for x in bad]:
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(*wi)
            v = mi.Vector3f(*wo)
            assert np.array_equal(np.array(b.eval(ctx, si, v)), np.zeros(3)), (source, wi, wo)
            assert b.pdf(ctx, si, v) == 0.0, (source, wi, wo)
            e, p = b.eval_pdf(ctx, si, v)
            assert np.array_equal(np.array(e), np.zeros(3)) and p == 0.0, (source, wi, wo)
        for wi in bad:
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(*wi)
            bs, w = b.sample(ctx, si, 0.5, mi.Point2f(0.3, 0.6))
            assert bs.pdf == 0.0 and np.array_equal(np.array(w), np.zeros(3)), (source, wi)


def test_jit_bad_input():
    use("llvm_ad_rgb")
    with pytest.raises(Exception, match="no-such-file"):
        mi.load_dict({"type": "brdftab", "source": "/nonexistent/no-such-file.btdb"})
    with pytest.raises(Exception, match="delta"):
        mi.load_dict({"type": "brdftab", "source": '{"model": "mirror"}'})
    b = mi.load_dict({"type": "brdftab", "source": '{"model": "ggx", "alpha": 0.3}',
                      "preset": "small"})
    si = dr.zeros(mi.SurfaceInteraction3f, 3)
    si.wi = mi.Vector3f([0, math.nan, 0], [0, 0, 0], [1, 1, -1])
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1)))
    assert np.isfinite(v[:, 0]).all() and (v[:, 1:] == 0).all()


def test_jit_nan_and_tiny_directions_give_the_scalar_variants_values():
    """The JIT variants gave NaN for a wo with a NaN x or y (the lookup's 0 times a cosine of
    NaN) and inf for a tiny non-unit wo (float32 |wo|² underflowed in `dr.normalize`); the
    scalar variants give 0 and the direction's value."""
    ctx = mi.BSDFContext()
    wi = (0.3, 0.1, 0.9)
    tiny = (1e-30, 0.0, 1e-30)
    use("scalar_rgb")
    scalar = mi.load_dict({"type": "brdftab", "source": GGX_SPEC, "preset": "small"})
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*wi)
    want = np.array(scalar.eval(ctx, si, mi.Vector3f(*tiny)))
    assert want.min() > 0
    assert np.allclose(want, np.array(scalar.eval(ctx, si, mi.Vector3f(1.0, 0.0, 1.0))))
    use("llvm_ad_rgb")
    b = mi.load_dict({"type": "brdftab", "source": GGX_SPEC, "preset": "small"})
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*wi)
    for wo in [(math.nan, 0.0, 1.0), (0.0, math.nan, 1.0), (math.inf, 0.0, 1.0)]:
        v = mi.Vector3f(*wo)
        assert np.array_equal(np.array(b.eval(ctx, si, v)).ravel(), np.zeros(3)), wo
        e, p = b.eval_pdf(ctx, si, v)
        assert np.array_equal(np.array(e).ravel(), np.zeros(3)), wo
        assert float(p[0]) == 0.0 and float(b.pdf(ctx, si, v)[0]) == 0.0, wo
    got = np.array(b.eval(ctx, si, mi.Vector3f(*tiny))).ravel()
    unit = np.array(b.eval(ctx, si, mi.Vector3f(1.0, 0.0, 1.0))).ravel()
    # The same direction as (1, 0, 1): the same value, to float32 rounding.
    assert np.allclose(got, unit, rtol=1e-5), (got, unit)
    # The JIT variant's table against the scalar variant's source: within the table's error.
    assert np.allclose(got, want, rtol=0.03), (got, want)
    assert float(b.pdf(ctx, si, mi.Vector3f(*tiny))[0]) > 0


def test_jit_sample_at_the_pole_is_the_librarys(rgl):
    """u.x = 0 draws the half vector at the pole: the mirror direction, where the map's
    Jacobian is 0. The JIT draw returned pdf 0 and weight 0 there (0/0), and its `pdf` of the
    returned float32 direction read the fold's other preimage, whose sum with wi is the
    direction's rounding (~1e-7), as 300 (paper_white: the library gives 21.4 for both)."""
    use("llvm_ad_rgb")
    src = os.path.join(rgl, "paper_white_rgb.bsdf")
    b = mi.load_dict({"type": "brdftab", "source": src})
    lib = brdftab.open(src)
    ctx = mi.BSDFContext()
    wi = np.array([0.3, 0.1, 0.9]) / np.linalg.norm([0.3, 0.1, 0.9])
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*[float(x) for x in wi])
    bs, w = b.sample(ctx, si, 0.5, mi.Point2f(0.0, 0.5))
    wo = np.array(bs.wo).ravel()
    mirror = np.array([-wi[0], -wi[1], wi[2]])
    assert np.allclose(wo, mirror, atol=1e-6), wo
    want = float(lib.pdf(mirror, wi))
    pdf = float(bs.pdf[0])
    # The density's limit at the pole, read at s = POLE_S in float32 (the library reads it in
    # float64): within 1 %, as the JIT and library densities agree elsewhere near the pole.
    assert abs(pdf / want - 1) < 0.01, (pdf, want)
    assert abs(float(b.pdf(ctx, si, bs.wo)[0]) / want - 1) < 0.01
    value = np.array(b.eval(ctx, si, bs.wo)).ravel()
    assert np.allclose(np.array(w).ravel(), value / pdf, rtol=1e-5)


def test_jit_spectral_evaluates_at_si_wavelengths():
    use("llvm_ad_rgb")  # skips without libLLVM
    use("llvm_ad_spectral")
    spec = '{"model": "lambert", "kd": {"wavelengths": [400, 700], "values": [0.2, 0.8]}}'
    b = mi.load_dict({"type": "brdftab", "source": spec, "preset": "small"})
    si = dr.zeros(mi.SurfaceInteraction3f, 2)
    si.wi = mi.Vector3f(0, 0, 1)
    si.wavelengths = mi.Spectrum([450, 500], [550, 560], [600, 610], [700, 710])
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(0.6, 0, 0.8)))
    want = brdftab.open(spec).eval_spectral([0, 0, 1], [0.6, 0, 0.8],
                                           np.array(si.wavelengths).T.ravel())
    np.testing.assert_allclose(v.T.ravel(), want * 0.8, rtol=0.02)


def test_scalar_flags_and_delta():
    use("scalar_rgb")
    F = mi.BSDFFlags
    m = mi.load_dict({"type": "brdftab", "source": '{"model": "mirror"}'})
    assert m.flags() & F.DeltaReflection and m.flags() & F.FrontSide
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.6, 0, 0.8)
    bs, w = m.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.3, 0.3))
    np.testing.assert_allclose(np.array(bs.wo), [-0.6, 0, 0.8], atol=1e-6)
    assert bs.pdf == 1 and np.all(np.array(w) > 0)
    assert np.all(np.array(m.eval(mi.BSDFContext(), si, bs.wo)) == 0)
    lam = mi.load_dict({"type": "brdftab", "source": '{"model": "lambert", "kd": 0.5}'})
    assert lam.flags() & F.DiffuseReflection
    assert not lam.flags() & F.GlossyReflection
    ggx = mi.load_dict({"type": "brdftab", "source": '{"model": "ggx", "alpha": 0.3}'})
    assert ggx.flags() & F.GlossyReflection and not ggx.flags() & F.DiffuseReflection
    # the library's lobes, not a guess from the model's name: a sum has both, a spec file too
    plastic = ('{"model": "sum", "terms": [{"model": "oren_nayar", "kd": 0.3, "sigma": 0.2},'
               ' {"model": "ggx", "alpha": 0.2}]}')
    both = mi.load_dict({"type": "brdftab", "source": plastic})
    assert both.flags() & F.GlossyReflection and both.flags() & F.DiffuseReflection
    # back side: zero
    si.wi = mi.Vector3f(0, 0, -1)
    assert np.all(np.array(ggx.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))) == 0)
    assert ggx.pdf(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1)) == 0


# A conductor whose n and k vary linearly between 400 and 700 nm, as the library's spec and as
# Mitsuba's `irregular` spectra (both interpolate linearly).
SPECTRAL_N = {"wavelengths": [400, 700], "values": [0.2, 1.4]}
SPECTRAL_K = {"wavelengths": [400, 700], "values": [3.0, 1.0]}


def _irregular(v):
    return {"type": "irregular", "wavelengths": ", ".join(map(str, v["wavelengths"])),
            "values": ", ".join(map(str, v["values"]))}


def test_scalar_spectral_mirror_weighs_each_wavelength_as_mitsubas_conductor():
    """A mirror's reflectance lives only in its sample: in a spectral variant the weight is
    the Fresnel term at each of the path's wavelengths (it was the mean of the RGB weights),
    as Mitsuba's own `conductor` gives it for the same n(λ), k(λ)."""
    use("scalar_spectral")
    spec = json.dumps({"model": "mirror", "fresnel": {"n": SPECTRAL_N, "k": SPECTRAL_K}})
    ours = mi.load_dict({"type": "brdftab", "source": spec})
    ref = mi.load_dict({"type": "conductor", "eta": _irregular(SPECTRAL_N),
                        "k": _irregular(SPECTRAL_K)})
    ctx = mi.BSDFContext()
    for t in (0.0, 0.6, 1.43):  # to 82°
        wi = [math.sin(t), 0.0, math.cos(t)]
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wi)
        si.wavelengths = mi.Spectrum([410, 480, 555, 690])
        (bs, w), (rbs, rw) = (b.sample(ctx, si, 0.5, mi.Point2f(0.3, 0.6)) for b in (ours, ref))
        np.testing.assert_allclose(np.array(bs.wo), np.array(rbs.wo), atol=1e-6)
        assert bs.pdf == rbs.pdf == 1 and bs.sampled_type == int(mi.BSDFFlags.DeltaReflection)
        # float32 arithmetic on both sides
        np.testing.assert_allclose(np.array(w), np.array(rw), rtol=1e-5)
        assert np.ptp(np.array(w)) > 0.1  # the four wavelengths differ: not one grey value


def test_scalar_sum_with_a_mirror_term_keeps_the_mirror():
    """A sum of a diffuse and a mirror term: draws of the mirror term are delta samples
    (DeltaReflection, pdf = the probability of that term, the library's weight), so the mean
    weight is the sum's albedo — it lost the mirror when the weight was recomputed from eval —
    in RGB and at each wavelength of a spectral variant."""
    spec = json.dumps({"model": "sum", "terms": [
        {"model": "lambert", "kd": 0.1},
        {"model": "mirror", "fresnel": {"n": SPECTRAL_N, "k": SPECTRAL_K}}]})
    theta = 0.5
    wi = [math.sin(theta), 0.0, math.cos(theta)]
    n = 4096
    u = [((k + 0.5) / n, 0.37) for k in range(n)]
    for variant, lam in (("scalar_rgb", None), ("scalar_spectral", [410.0, 480.0, 555.0, 690.0])):
        use(variant)
        b = mi.load_dict({"type": "brdftab", "source": spec})
        assert b.flags() & mi.BSDFFlags.DeltaReflection and b.flags() & mi.BSDFFlags.DiffuseReflection
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wi)
        if lam:
            si.wavelengths = mi.Spectrum(lam)
        ctx = mi.BSDFContext()
        total, most, deltas = 0.0, 0.0, 0
        for x in u:
            bs, w = b.sample(ctx, si, 0.5, mi.Point2f(*x))
            w = np.array(w)
            total, most = total + w, max(most, w.max())
            if bs.sampled_type & int(mi.BSDFFlags.Delta):
                deltas += 1
                assert 0 < bs.pdf < 1 and b.pdf(ctx, si, bs.wo) < 10  # not in the smooth pdf
        want = (brdftab.open(spec).albedo(theta) if lam is None else
                brdftab.open(spec, wavelengths=lam).albedo(theta))
        # each branch's weight is its reflectance / its probability; stratified u leave at most
        # two strata's weights
        np.testing.assert_allclose(total / n, want, atol=2 * most / n)
        assert 0 < deltas < n


def test_jit_spectral_reads_rgb_tables_as_the_scalar_variant(tmp_path):
    """An RGB table in a spectral JIT variant is read at each wavelength as the library reads
    RGB channels (`eval_spectral`, the scalar variant's reading) — not as one grey value."""
    use("llvm_ad_rgb")  # skips without libLLVM
    use("llvm_ad_spectral")
    spec = '{"model": "ggx", "alpha": 0.4, "fresnel": {"conductor": "Au"}}'
    path = str(tmp_path / "au.btdb")
    brdftab.bake(spec, path, preset="small")
    b = mi.load_dict({"type": "brdftab", "source": path})
    n = 64
    wi, wo = random_dirs(n, 3, 0.2), random_dirs(n, 4, 0.2)
    lam = np.array([420.0, 500.0, 560.0, 680.0])
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*wi.T)
    si.wavelengths = mi.Spectrum(*[np.full(n, x) for x in lam])
    v = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(*wo.T))).T
    want = brdftab.open(path).eval_spectral(wi, wo, lam) * wo[:, 2:3]
    # the JIT lookup in float32 against the library's
    np.testing.assert_allclose(v, want, rtol=1e-4, atol=1e-6)
    assert np.all(np.ptp(want, axis=1) > 0.3 * want.max(axis=1))  # gold: not grey


def test_a_refractor_is_refused_not_rendered_black():
    """The plugin is a BRDF (front side only): a refractor's draws all lie below the surface,
    so it rendered black; it is refused with a pointer to Mitsuba's dielectric."""
    for variant in ("scalar_rgb", "scalar_spectral"):
        use(variant)
        for spec in ('{"model": "refractor", "eta": 1.5}',
                     '{"model": "sum", "terms": [{"model": "ggx", "alpha": 0.2},'
                     ' {"model": "refractor", "eta": 1.5}]}'):
            with pytest.raises(Exception, match="dielectric"):
                mi.load_dict({"type": "brdftab", "source": spec})


def test_jit_refuses_a_sum_with_a_mirror_term():
    """A table cannot hold a delta lobe: a JIT variant refuses a sum with a mirror term (it
    dropped the mirror) as it refuses a mirror, and points to the scalar variants."""
    use("llvm_ad_rgb")  # skips without libLLVM
    spec = ('{"model": "sum", "terms": [{"model": "lambert", "kd": 0.1},'
            ' {"model": "mirror"}]}')
    with pytest.raises(Exception, match="scalar variant"):
        mi.load_dict({"type": "brdftab", "source": spec})


GGX_SPEC = '{"model": "ggx", "alpha": 0.3, "fresnel": {"conductor": "Cu"}}'


def test_a_database_table_named_like_a_file_is_the_stored_table(tmp_path):
    """`db.btdb#paper.bsdf` names the stored table `paper.bsdf`: the plugin classified the
    SOURCE by its ending and re-baked the table as an RGL file (17.5 M values for a 197 k-value
    table, and `export_table` gave that bake back, not the user's table)."""
    import brdftab.mitsuba as bm

    db = brdftab.Database(tmp_path / "kind.btdb")
    db.add(GGX_SPEC, "ggx.json", preset="small")
    db.add(GGX_SPEC, "paper.bsdf", preset="small")
    db.add(GGX_SPEC, "scan.binary", preset="small")
    for name in db.names():
        assert bm.brdftab_kind(db.source(name)) == "table"
    assert bm.brdftab_kind('{"model": "lambert"}') == "spec"
    assert bm.brdftab_kind("x/paper.bsdf") == "rgl"
    use("llvm_ad_rgb")  # skips without libLLVM
    stored = brdftab.open(db.source("paper.bsdf")).table().values.size
    b = mi.load_dict({"type": "brdftab", "source": db.source("paper.bsdf"),
                      "cache_dir": str(tmp_path / "cache")})
    assert b.table.n_values == stored
    assert not (tmp_path / "cache").exists()  # nothing was baked


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_an_rgb_variant_refuses_three_wavelengths(tmp_path, variant):
    """A table at 450, 550 and 650 nm has three channels but they are not R, G, B: an RGB
    variant read its 450 nm channel as red (a blue Lambert rendered red)."""
    use(variant)
    table = tmp_path / "blue.btdb"
    brdftab.bake('{"model": "lambert", "kd": [0.02, 0.05, 0.25]}', table, preset="small",
                 wavelengths=[450, 550, 650])
    with pytest.raises(Exception, match="R, G, B"):
        mi.load_dict({"type": "brdftab", "source": str(table)})


def test_a_scalar_variant_loads_a_scene_written_for_the_jit_variants(tmp_path):
    """The JIT table's properties (preset, grid, cache, cache_dir, sampling_res) made Mitsuba's
    scalar variants refuse the scene ("unreferenced property"); they are accepted and ignored
    there: a scalar variant evaluates the source itself."""
    import brdftab.mitsuba as bm

    use("scalar_rgb")
    props = {"preset": "small", "cache": False, "cache_dir": str(tmp_path), "sampling_res": 32}
    assert set(props) | {"grid"} == set(bm.JIT_TABLE_PROPERTIES)
    b = mi.load_dict({"type": "brdftab", "source": GGX_SPEC, **props})
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.3, 0.1, 0.948683)
    wo = mi.Vector3f(-0.3, 0.0, 0.953939)
    want = brdftab.open(GGX_SPEC).eval([-0.3, 0.0, 0.953939], [0.3, 0.1, 0.948683])
    got = np.array(b.eval(mi.BSDFContext(), si, wo)) / 0.953939
    np.testing.assert_allclose(got, want, rtol=1e-5)
    assert not list(tmp_path.iterdir())  # nothing baked or cached



@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_table_properties_are_checked_in_every_variant(variant):
    """`cache: "no"` was true (bool of a string) and `sampling_res` 0..2 were taken (the JIT
    draw's density then 5.7x its pdf), -4 a raw OverflowError; the scalar variants took
    anything. Now both refuse the same values, and accept the same ones."""
    import brdftab.mitsuba as bm

    use(variant)
    for bad in [{"sampling_res": 2}, {"sampling_res": -4}, {"sampling_res": "abc"},
                {"sampling_res": 16.5}, {"cache": "maybe"}, {"cache_dir": 5},
                {"cache_dir": ""}]:
        with pytest.raises(Exception, match="brdftab plugin: `(sampling_res|cache|cache_dir)`"):
            mi.load_dict({"type": "brdftab", "source": GGX_SPEC, **bad})
    # `preset`/`grid` as the bake takes them: `preset: "huge"` loaded in the scalar variants
    # (which ignore the value) and failed in the JIT ones (which bake with it).
    for bad in [{"preset": "huge"}, {"grid": "32x17"}, {"preset": "small", "grid": "nope"}]:
        with pytest.raises(Exception, match="invalid argument `(preset|grid)`"):
            mi.load_dict({"type": "brdftab", "source": GGX_SPEC, "cache": False, **bad})
    assert bm._bool_prop({"cache": "no"}, "cache", True) is False
    assert bm._bool_prop({"cache": "True"}, "cache", False) is True
    mi.load_dict({"type": "brdftab", "source": GGX_SPEC, "preset": "small", "cache": "false",
                  "sampling_res": bm.SAMPLING_RES_RANGE[0]})


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_preset_or_grid_with_a_table_source_is_refused_in_every_variant(tmp_path, variant):
    """A table source is evaluated as stored: `preset` made the JIT variants bake it again
    from itself (0.86067 against the table's 0.86206 at one pair) while the scalar ones read
    it as it is, so one scene file gave two materials."""
    use(variant)
    table = tmp_path / "g.btdb"
    brdftab.bake(GGX_SPEC, str(table), preset="small")
    for key, value in [("preset", "small"), ("grid", "16x1x16x9")]:
        with pytest.raises(Exception, match=f"is a table.*`{key}`"):
            mi.load_dict({"type": "brdftab", "source": str(table), key: value})
    mi.load_dict({"type": "brdftab", "source": str(table)})  # without them: as stored


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_a_scene_file_names_its_material_as_it_would_for_measured(rgl, tmp_path, variant,
                                                                  monkeypatch):
    """A scene written for Mitsuba's `measured` says `filename`, relative to the scene file;
    the plugin took only `source`, relative to the working directory."""
    use(variant)
    scene_dir = tmp_path / "scene"
    scene_dir.mkdir()
    shutil.copy(rgl / RGL_FILE, scene_dir / "material.bsdf")
    db = brdftab.Database(scene_dir / "lib.btdb")
    db.add(GGX_SPEC, "ggx", preset="small")
    cache = {} if variant.startswith("scalar") else {"cache_dir": str(tmp_path / "cache")}
    extra = "".join(f'<string name="{k}" value="{v}"/>' for k, v in cache.items())
    monkeypatch.chdir(tmp_path)  # not the scene's directory: the resolver finds the files
    wi, wo = random_dirs(8, 1, 0.2), random_dirs(8, 2, 0.2)
    for prop, value, want in [
        ("filename", "material.bsdf", str(rgl / RGL_FILE)),
        ("source", "lib.btdb#ggx", db.source("ggx")),
    ]:
        xml = scene_dir / f"{prop}.xml"
        xml.write_text(
            f'<bsdf version="3.0.0" type="brdftab"><string name="{prop}" value="{value}"/>'
            f"{extra}</bsdf>"
        )
        got = mi.load_file(str(xml))
        ref = mi.load_dict({"type": "brdftab", "source": want, **cache})
        a, b = eval_both(variant, got, ref, wi, wo)
        np.testing.assert_array_equal(a, b)
        assert np.all(a > 0)
    with pytest.raises(Exception, match="not both"):
        mi.load_dict({"type": "brdftab", "source": "a.bsdf", "filename": "a.bsdf"})


def _calls(variant, b, ctx, wi, wo, u):
    """eval, pdf, eval_pdf and sample of ``b`` at one pair, as numpy arrays."""
    si = mi.SurfaceInteraction3f() if variant.startswith("scalar") else dr.zeros(
        mi.SurfaceInteraction3f, 1)
    wi, wo, u = ([float(x) for x in v] for v in (wi, wo, u))
    si.wi, v, u2 = mi.Vector3f(*wi), mi.Vector3f(*wo), mi.Point2f(*u)
    e, p = b.eval_pdf(ctx, si, v)
    bs, w = b.sample(ctx, si, 0.5, u2)
    return dict(eval=np.array(b.eval(ctx, si, v)).ravel(), pdf=np.array(b.pdf(ctx, si, v)).ravel(),
                eval_pdf=np.concatenate([np.array(e).ravel(), np.array(p).ravel()]),
                sample=np.concatenate([np.array(bs.pdf).ravel(), np.array(w).ravel()]))


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_a_context_that_excludes_the_component_gets_nothing(variant):
    """A ``BSDFContext`` whose type mask or component leaves out the plugin's one component
    (glossy reflection for GGX) got the full BSDF, where Mitsuba's own plugins (``measured``,
    ``roughconductor``) give zeros: eval, pdf, eval_pdf and sample."""
    use(variant)
    F = mi.BSDFFlags
    b = mi.load_dict({"type": "brdftab", "source": GGX_SPEC, "preset": "small", "cache": False})
    wi, wo, u = [0.3, 0.1, 0.948683], [-0.3, 0.0, 0.953939], [0.3, 0.6]
    full = _calls(variant, b, mi.BSDFContext(), wi, wo, u)
    assert all(np.all(v > 0) for v in full.values())
    other = mi.BSDFContext()
    other.component = 1
    for ctx in [mi.BSDFContext(mi.TransportMode.Radiance, F.DiffuseReflection),
                mi.BSDFContext(mi.TransportMode.Radiance, F.DeltaReflection), other]:
        got = _calls(variant, b, ctx, wi, wo, u)
        assert all(not np.any(v) for v in got.values()), (ctx, got)
    for ctx in [mi.BSDFContext(mi.TransportMode.Radiance, F.GlossyReflection),
                mi.BSDFContext(mi.TransportMode.Radiance, F.GlossyReflection | F.DiffuseReflection)]:
        got = _calls(variant, b, ctx, wi, wo, u)
        for k, v in full.items():
            np.testing.assert_array_equal(got[k], v)


PHONG_ORIGINAL = '{"model": "phong", "ks": 0.5, "n": 20}'  # k_s cos^n ψ / cos θ′: not reciprocal


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_importance_transport_evaluates_the_adjoint(variant):
    """In importance transport (a light tracer: ``ptracer``) ``si.wi`` points towards the light's
    side of the path, so for a source that is not reciprocal the plugin must give the adjoint,
    f(wo, si.wi) cos θo, for ``path`` and ``ptracer`` to render one material. It gave
    f(si.wi, wo) cos θo in both modes (the original Phong's 1 / cos θ′ on the wrong side)."""
    use(variant)
    b = mi.load_dict({"type": "brdftab", "source": PHONG_ORIGINAL, "preset": "small",
                      "cache": False})
    a = np.array([0.8, 0.0, 0.6])      # θ 53°
    c = np.array([-0.75, 0.1, 0.6538])  # near a's mirror image, θ 49°
    c /= np.linalg.norm(c)
    rad = mi.BSDFContext(mi.TransportMode.Radiance)
    imp = mi.BSDFContext(mi.TransportMode.Importance)
    f_rad = _calls(variant, b, rad, c, a, [0.5, 0.5])["eval"] / a[2]
    f_imp = _calls(variant, b, imp, a, c, [0.5, 0.5])["eval"] / c[2]
    # The same f_r at the same pair, read with the roles the mode gives the directions.
    np.testing.assert_allclose(f_imp, f_rad, rtol=1e-6)
    f_swapped = _calls(variant, b, rad, a, c, [0.5, 0.5])["eval"] / c[2]
    # 1 / cos θ′ of the two directions: 0.6538 / 0.6 apart, far from equal.
    assert np.all(np.abs(f_swapped / f_imp - 1) > 0.05)
    # A draw's weight in importance transport is its eval over its pdf.
    for u in ([0.2, 0.7], [0.6, 0.1], [0.9, 0.9]):
        got = _calls(variant, b, imp, a, c, u)
        if variant.startswith("scalar"):
            si = mi.SurfaceInteraction3f()
        else:
            si = dr.zeros(mi.SurfaceInteraction3f, 1)
        si.wi = mi.Vector3f(*[float(x) for x in a])
        bs, w = b.sample(imp, si, 0.5, mi.Point2f(*u))
        e = np.array(b.eval(imp, si, bs.wo)).ravel()
        pdf = float(np.array(bs.pdf).ravel()[0])
        assert pdf > 0
        np.testing.assert_allclose(np.array(w).ravel(), e / pdf, rtol=1e-5)


def _one_pair(variant, b, nm=None):
    """eval and sample's weight of ``b`` at one pair (``nm``: a spectral variant's wavelengths)."""
    si = mi.SurfaceInteraction3f() if variant.startswith("scalar") else dr.zeros(
        mi.SurfaceInteraction3f, 1)
    si.wi = mi.Vector3f(0.3, 0.1, 0.948683)
    if nm is not None:
        si.wavelengths = mi.Spectrum(nm) if not mi.is_polarized else mi.UnpolarizedSpectrum(nm)
    ctx = mi.BSDFContext()
    e = b.eval(ctx, si, mi.Vector3f(-0.3, 0.0, 0.953939))
    _, w = b.sample(ctx, si, 0.5, mi.Point2f(0.3, 0.6))
    return np.array(e), np.array(w)


@pytest.mark.parametrize("variant", ["scalar_spectral_polarized", "llvm_ad_spectral_polarized"])
def test_polarized_variants_get_a_depolarizer(variant):
    """A polarized variant's Spectrum is a Mueller matrix: the plugin filled all 16 entries
    with f_r cos θo (Stokes Q, U, V fed into the intensity at the next bounce) or raised. Like
    Mitsuba's ``measured`` and ``diffuse``, it now gives a depolarizer: f_r cos θo in the
    [0, 0] entry, 0 elsewhere, the unpolarized variant's value."""
    nm = [450.0, 520.0, 600.0, 680.0]
    plain = variant.replace("_polarized", "")
    use(plain)
    d = {"type": "brdftab", "source": GGX_SPEC, "preset": "small", "cache": False}
    want_e, want_w = _one_pair(plain, mi.load_dict(d), nm)
    use(variant)
    e, w = _one_pair(variant, mi.load_dict(d), nm)
    for got, want in ((e, want_e), (w, want_w)):
        got = got.reshape(4, 4, -1)
        np.testing.assert_array_equal(got[0, 0], want.ravel())
        assert np.all(want > 0)
        got[0, 0] = 0
        assert not np.any(got)
    # A render: a depolarizer's path throughput is the unpolarized one (products with exact
    # zeros), so the images agree to float32 rounding. (A Mueller matrix returned from the
    # plugin's symbolic branch made Dr.Jit's LLVM backend emit invalid IR here.)
    scene = {"type": "scene", "integrator": {"type": "path", "max_depth": 3},
             "sensor": {"type": "perspective", "fov": 30,
                        "to_world": mi.ScalarTransform4f().look_at([0, -4, 2.5], [0, 0, 0],
                                                                   [0, 0, 1]),
                        "film": {"type": "hdrfilm", "width": 8, "height": 8}},
             "sphere": {"type": "sphere", "bsdf": d},
             "env": {"type": "constant"}}
    img = np.array(mi.render(mi.load_dict(scene), spp=4, seed=1))
    use(plain)
    want = np.array(mi.render(mi.load_dict(scene), spp=4, seed=1))
    assert want.mean() > 0.1
    np.testing.assert_allclose(img, want, rtol=1e-5, atol=1e-6)


def test_a_monochrome_variant_reads_the_luminance():
    """``llvm_ad_mono``: an RGB source failed inside Dr.Jit ("dr.if_stmt(): encountered an
    exception") at the first eval. It now reads the luminance of the RGB value, as Mitsuba's
    RGB inputs do in monochrome variants."""
    use("llvm_ad_rgb")
    d = {"type": "brdftab", "source": GGX_SPEC, "preset": "small", "cache": False}
    rgb_e, rgb_w = _one_pair("llvm_ad_rgb", mi.load_dict(d))
    use("llvm_ad_mono")
    e, w = _one_pair("llvm_ad_mono", mi.load_dict(d))
    # Rec. 709 luminance weights (mi.luminance), summed in float32.
    lum = np.array([0.212671, 0.715160, 0.072169])
    for got, rgb in ((e, rgb_e), (w, rgb_w)):
        np.testing.assert_allclose(got.ravel(), lum @ rgb.reshape(3), rtol=1e-6)


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test_errors_name_the_property(variant):
    """``source: 3`` said the property was "required" (it was given, as an integer);
    ``filename: 3.5`` was read as the file "3.5"; a missing file's error did not say which
    property named it. Each now names the property and what was wrong with it."""
    use(variant)
    for key, bad, kind in [("source", 3, "int"), ("filename", 3.5, "float"),
                           ("source", True, "bool")]:
        with pytest.raises(Exception, match=f"brdftab plugin: `{key}` must be a string, got "
                                            f"{kind}"):
            mi.load_dict({"type": "brdftab", key: bad})
    with pytest.raises(Exception, match="brdftab plugin: `filename` 'no-such-file.bsdf': "
                                        ".*no-such-file.bsdf"):
        mi.load_dict({"type": "brdftab", "filename": "no-such-file.bsdf"})
    with pytest.raises(Exception, match="brdftab plugin: `source` "):
        mi.load_dict({"type": "brdftab", "source": '{"model": "nope"}'})
    # The process goes on: a good material loads after the errors.
    mi.load_dict({"type": "brdftab", "source": '{"model": "lambert", "kd": 0.5}',
                  "preset": "small", "cache": False})
