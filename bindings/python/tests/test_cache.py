"""The cache of baked tables (issue 26, item 3): bake once, load from disk after, safe under
concurrent loads from many processes, used by the Mitsuba plugin."""

import multiprocessing
import os
import pathlib

import numpy as np
import pytest

import brdftab
from conftest import unavailable

SPEC = '{"model": "ggx", "alpha": 0.3, "fresnel": {"conductor": "Cu"}}'


def tables(d):
    return sorted(p.name for p in pathlib.Path(d).iterdir() if p.suffix == ".btdb")


def test_a_second_call_is_a_hit_with_the_same_table(tmp_path):
    a = brdftab.bake_cached(SPEC, tmp_path, preset="small")
    assert a["hit"] is False and tables(tmp_path) == [os.path.basename(a["path"])]
    mtime = os.stat(a["path"]).st_mtime_ns
    b = brdftab.bake_cached(SPEC, str(tmp_path), preset="small")
    assert b == {"path": a["path"], "hit": True}
    assert os.stat(a["path"]).st_mtime_ns == mtime, "a hit does not rewrite the file"
    # The cached table is the table `bake` makes with the same settings.
    brdftab.bake(SPEC, str(tmp_path / "direct.btdb"), preset="small")
    wi = np.array([[0.3, 0.1, 0.9], [0.0, 0.0, 1.0]])
    np.testing.assert_array_equal(brdftab.open(a["path"]).eval(wi, wi[::-1].copy()),
                                  brdftab.open(str(tmp_path / "direct.btdb")).eval(wi, wi[::-1].copy()))
    # Other settings, another source file content: other keys.
    c = brdftab.bake_cached(SPEC, tmp_path, preset="small", codec="f32")
    assert c["hit"] is False and c["path"] != a["path"]


def test_an_edited_source_file_is_baked_again(tmp_path):
    f = tmp_path / "m.json"
    f.write_text('{"model": "lambert", "kd": 0.2}')
    a = brdftab.bake_cached(str(f), tmp_path / "c", preset="small")
    f.write_text('{"model": "lambert", "kd": 0.4}')
    b = brdftab.bake_cached(str(f), tmp_path / "c", preset="small")
    assert not b["hit"] and b["path"] != a["path"]
    one = brdftab.open(b["path"]).eval([0, 0, 1], [0, 0, 1])
    np.testing.assert_allclose(one, 0.4, rtol=2e-3)  # Lambert: f_r = kd


def test_a_damaged_cache_file_is_refreshed(tmp_path):
    a = brdftab.bake_cached(SPEC, tmp_path, preset="small")
    pathlib.Path(a["path"]).write_bytes(b"garbage")
    with pytest.raises(brdftab.Error):
        brdftab.open(a["path"])
    b = brdftab.bake_cached(SPEC, tmp_path, refresh=True, preset="small")
    assert b == {"path": a["path"], "hit": False}
    brdftab.open(b["path"])


def test_the_default_directory_is_brdftab_cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("BRDFTAB_CACHE_DIR", str(tmp_path / "env"))
    a = brdftab.bake_cached(SPEC, preset="small")
    assert pathlib.Path(a["path"]).parent == tmp_path / "env"
    with pytest.raises(ValueError, match="preset"):
        brdftab.bake_cached(SPEC, preset="huge")
    with pytest.raises(TypeError):
        brdftab.bake_cached(SPEC, no_such_setting=1)


def _load(args):
    d, spec = args
    r = brdftab.bake_cached(spec, d, preset="small")
    t = brdftab.open(r["path"], eager=True)  # every chunk read: a torn file would fail here
    return r["path"], t.eval([0.3, 0.1, 0.9], [0, 0, 1]).tolist(), r["hit"]


def test_concurrent_loads_from_many_processes(tmp_path):
    """Eight processes ask for the same table at once: one bakes it (the others wait on the
    key's lock and get the hit), every one gets a whole table, the same values, and one file is
    left (no temporary files)."""
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(4) as pool:
        out = pool.map(_load, [(str(tmp_path), SPEC)] * 8)
    assert len({p for p, _, _ in out}) == 1
    assert all(v == out[0][1] for _, v, _ in out)
    assert sum(not hit for _, _, hit in out) == 1, "one bake"
    names = os.listdir(tmp_path)
    assert tables(tmp_path) == [os.path.basename(out[0][0])]
    assert not [n for n in names if ".tmp" in n], names


def test_the_mitsuba_plugin_bakes_once(rgl, tmp_path):
    try:
        import mitsuba as mi
    except ImportError:
        unavailable("mitsuba is not installed (pip install mitsuba)")
    try:
        mi.set_variant("llvm_ad_rgb")
    except Exception:
        unavailable("llvm_ad_rgb needs libLLVM (apt-get install libllvm19; DRJIT_LIBLLVM_PATH)")
    import brdftab.mitsuba

    brdftab.mitsuba.register()
    f = str(rgl / "cc_ibiza_sunset_rgb.bsdf")
    d = tmp_path / "mi-cache"
    a = mi.load_dict({"type": "brdftab", "source": f, "cache_dir": str(d)})
    [name] = tables(d)
    mtime = os.stat(d / name).st_mtime_ns
    b = mi.load_dict({"type": "brdftab", "source": f, "cache_dir": str(d)})
    assert tables(d) == [name] and os.stat(d / name).st_mtime_ns == mtime
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.3, 0.1, 0.9) / np.linalg.norm([0.3, 0.1, 0.9])
    wo = mi.Vector3f(-0.2, 0.0, 0.98) / np.linalg.norm([-0.2, 0.0, 0.98])
    ctx = mi.BSDFContext()
    np.testing.assert_array_equal(np.array(a.eval(ctx, si, wo)), np.array(b.eval(ctx, si, wo)))
    # `cache: false` bakes in memory and writes nothing.
    mi.load_dict({"type": "brdftab", "source": f, "cache": False, "cache_dir": str(tmp_path / "no")})
    assert not (tmp_path / "no").exists()
