"""The Mitsuba plugin's table values as a differentiable scene parameter (JIT variants): the
gradient of eval, eval_pdf and sample's weight with respect to them, edits through
``mi.SceneParameters``, an optimization, and the edited table exported as a brdftab table."""

import importlib.util
import pathlib

import numpy as np
import pytest

import brdftab

from conftest import unavailable

try:
    import drjit as dr
    import mitsuba as mi
except ImportError:
    unavailable("mitsuba is not installed (pip install mitsuba)")

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "optimize_values.py"
EPS32 = float(np.finfo(np.float32).eps)
GGX = '{"model": "ggx", "alpha": 0.3, "fresnel": {"conductor": "Cu"}}'


def use_llvm():
    try:
        mi.set_variant("llvm_ad_rgb")
        dr.eval(mi.Float(1.0) + 1)
    except Exception:
        unavailable("llvm_ad_rgb needs libLLVM (apt-get install libllvm19; DRJIT_LIBLLVM_PATH)")
    import brdftab.mitsuba

    brdftab.mitsuba.register()


@pytest.fixture(scope="module")
def tables(tmp_path_factory, rgl):
    """Three layouts: a model's small preset (kernel, float32 values), an RGL file's default
    table (kernel, packed f16 codes, albedo calibration), a nearest-lookup grid."""
    d = tmp_path_factory.mktemp("values")
    out = {}
    brdftab.bake(GGX, str(d / "ggx.btdb"), preset="small", calibrate=False)
    out["ggx_small"] = str(d / "ggx.btdb")
    brdftab.bake(str(rgl / "paper_white_rgb.bsdf"), str(d / "pw.btdb"))
    out["rgl_default"] = str(d / "pw.btdb")
    brdftab.bake('{"model": "lambert", "kd": [0.2, 0.4, 0.6]}', str(d / "lam.btdb"),
                 grid="8x1x8x16", param="inout", symmetry="isotropic,bilateral")
    out["inout_grid"] = str(d / "lam.btdb")
    return out


def directions(n, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.05
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


def queries(n=1024, seed=7):
    wi, wo = directions(n, seed), directions(n, seed + 1)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(wi.T)
    u1 = np.random.default_rng(seed + 2).uniform(size=n).astype(np.float32)
    u2 = np.random.default_rng(seed + 3).uniform(size=(2, n)).astype(np.float32)
    return si, mi.Vector3f(wo.T), mi.Float(u1), mi.Point2f(u2)


def outputs(bsdf, q):
    """eval, eval_pdf's value and sample's weight (n × 3 each, float64) and the draws."""
    si, wo, u1, u2 = q
    ctx = mi.BSDFContext()
    f = bsdf.eval(ctx, si, wo)
    g, _ = bsdf.eval_pdf(ctx, si, wo)
    bs, w = bsdf.sample(ctx, si, u1, u2)
    return f, g, w, bs


@pytest.mark.parametrize("case", ["ggx_small", "rgl_default", "inout_grid"])
def test_values_are_differentiable_and_lookups_are_linear_in_them(tables, case):
    """``values`` is a differentiable parameter; eval, eval_pdf and sample's weight are linear
    in it, so the reverse-mode gradient of L = Σ c·(f + g + w) is exactly the change of L when
    one value moves by 1: compared for the entries with the largest gradients, to the float32
    rounding of the lanes that change."""
    use_llvm()
    bsdf = mi.load_dict({"type": "brdftab", "source": tables[case]})
    params = mi.traverse(bsdf)
    assert "values" in params
    assert not params.properties["values"][3] & mi.ParamFlags.NonDifferentiable
    v0 = np.array(params["values"])
    q = queries()
    coef = mi.Vector3f(1.0, 2.0, 3.0)

    def total(values):
        params["values"] = values
        params.update()
        f, g, w, _ = outputs(bsdf, q)
        lanes = [dr.sum(x * coef) for x in (f, g, w)]  # per lane, float32
        return lanes, [np.array(x, np.float64) for x in lanes]

    V = mi.Float(v0)
    dr.enable_grad(V)
    lanes, base = total(V)
    dr.backward(dr.sum(lanes[0] + lanes[1] + lanes[2]))
    grad = np.array(dr.grad(V), np.float64)
    assert np.count_nonzero(grad) > 100
    for k in np.argsort(-np.abs(grad))[:4]:
        v1 = v0.copy()
        v1[k] += 1.0
        _, moved = total(mi.Float(v1))
        diff = sum((m - b).sum() for m, b in zip(moved, base))
        changed = [m != b for m, b in zip(moved, base)]
        n = sum(int(c.sum()) for c in changed)
        assert n > 0
        # Each changed lane (float32) is a few roundings from its exact linear form, and the
        # gradient sums n float32 contributions: a few ulps of what those lanes hold, each way.
        held = sum((np.abs(m[c]) + np.abs(b[c])).sum() for m, b, c in zip(moved, base, changed))
        bound = 8 * EPS32 * (held + n * abs(grad[k]))
        assert abs(diff - grad[k]) <= bound, (k, diff, grad[k], bound)


def test_edited_values_scale_lookups_exactly_and_export_as_a_table(tables, tmp_path):
    """Values doubled through mi.SceneParameters double eval and sample's weight bit for bit
    (the packed f16 codes give way to the float32 values, which hold the same numbers); the
    draws and pdf do not move (the sampling distributions are those of the loaded table). The
    exported table, saved and opened by the library, evaluates to twice the original."""
    use_llvm()
    src = tables["rgl_default"]
    bsdf = mi.load_dict({"type": "brdftab", "source": src})
    assert bsdf.table.kernel["packed"] is not None
    params = mi.traverse(bsdf)
    q = queries(512, 11)
    f0, g0, w0, bs0 = outputs(bsdf, q)
    v0 = np.array(params["values"])
    params["values"] = mi.Float(2.0 * v0)
    params.update()
    f1, g1, w1, bs1 = outputs(bsdf, q)
    for a, b in ((f0, f1), (g0, g1), (w0, w1)):
        np.testing.assert_array_equal(2.0 * np.array(a), np.array(b))
    np.testing.assert_array_equal(np.array(bs0.wo), np.array(bs1.wo))
    np.testing.assert_array_equal(np.array(bs0.pdf), np.array(bs1.pdf))

    out = tmp_path / "edited.btdb"
    bsdf.export_table().save(str(out), codec="f32")
    wi, wo = directions(400, 3), directions(400, 4)
    np.testing.assert_allclose(brdftab.open(str(out)).eval(wi, wo),
                               2.0 * brdftab.open(src).eval(wi, wo), rtol=1e-6, atol=0)

    params["values"] = mi.Float(v0[:-3])
    with pytest.raises(brdftab.Error, match="values"):
        params.update()


def test_resample_follows_the_edited_values(tables, tmp_path):
    """After an edit that moves the lobe (the table's half of smaller θh made ten times
    brighter) the plugin samples with the loaded table's distributions; resample() rebuilds
    them, and its pdf is then bit for bit that of a plugin loading the exported table."""
    use_llvm()
    bsdf = mi.load_dict({"type": "brdftab", "source": tables["ggx_small"]})
    params = mi.traverse(bsdf)
    v = np.array(params["values"])
    v[: v.size // 2] *= 10.0
    params["values"] = mi.Float(v)
    params.update()
    si, wo, _, _ = queries(512, 5)
    ctx = mi.BSDFContext()
    before = np.array(bsdf.pdf(ctx, si, wo))
    bsdf.resample()
    after = np.array(bsdf.pdf(ctx, si, wo))
    assert not np.array_equal(before, after)
    out = tmp_path / "edited.btdb"
    bsdf.export_table().save(str(out), codec="f32")
    fresh = mi.load_dict({"type": "brdftab", "source": str(out)})
    np.testing.assert_array_equal(after, np.array(fresh.pdf(ctx, si, wo)))


def test_a_renders_gradient_obeys_eulers_identity(tables):
    """A render of the sphere alone (emitters hidden) is linear and homogeneous in the values,
    so its gradient g satisfies Σ v·g = L (Euler's identity) — through Mitsuba's prb, its
    emitter and BSDF sampling and the plugin's eval, eval_pdf and sample. prb estimates g with
    other samples than L, so per seed the two differ by Monte Carlo noise; over five seeds
    their mean relative difference must be within five standard errors of zero."""
    use_llvm()
    sc = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "prb", "max_depth": 2, "hide_emitters": True},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(
                       origin=[0, -4, 1.5], target=[0, 0, 0], up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": 24, "height": 24, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": 32}},
        "sphere": {"type": "sphere", "bsdf": {"type": "brdftab", "source": tables["rgl_default"]}},
        "light": {"type": "point", "position": [2, -2, 3],
                  "intensity": {"type": "rgb", "value": 20}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.2}},
    })
    params = mi.traverse(sc)
    key = "sphere.bsdf.values"
    d = []
    for seed in range(5):
        V = params[key]
        dr.disable_grad(V)
        L = np.array(mi.render(sc, params, seed=seed), np.float64).sum()
        dr.enable_grad(V)
        params.update()
        dr.backward(dr.sum(mi.render(sc, params, seed=seed), axis=None))
        g = np.array(dr.grad(V), np.float64)
        v = np.array(dr.detach(V), np.float64)
        d.append((v * g).sum() / L - 1.0)
    d = np.array(d)
    assert abs(d.mean()) <= 5 * d.std(ddof=1) / np.sqrt(len(d)), d


def test_the_example_fits_a_table_to_renders_of_roughconductor(tmp_path):
    """bindings/python/examples/optimize_values.py, shortened: Adam on the values of a Lambert
    table against renders of Mitsuba's roughconductor (GGX copper) from three views. The image
    loss falls to under half in sixteen steps, and the saved table is the fitted one: loaded
    again by the plugin, it renders (fresh samples) at under half the start table's loss, on
    the start's grid."""
    use_llvm()
    spec = importlib.util.spec_from_file_location("optimize_values", EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    out = tmp_path / "fitted.btdb"
    r = example.optimize(str(out), iterations=16, size=24, spp=4, log=None)
    assert r["losses"][-1] < 0.5 * r["losses"][0], r
    assert r["saved"] < 0.5 * r["start"], r
    shape = brdftab.open(example.START).table(preset="small").values.shape
    assert brdftab.open(str(out)).table().values.shape == shape
