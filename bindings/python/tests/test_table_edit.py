"""Tables edited in numpy: `Table.with_values`, `Table.save`, `Table.open`."""

import pickle

import numpy as np
import pytest

import brdftab

GGX = '{"model": "ggx", "alpha": 0.3, "ks": 0.8}'


def upper(n, seed=0):
    """n random directions of the upper hemisphere (not normalized)."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return v


WI, WO = upper(2000), upper(2000, 1)


def baked(tmp_path, name, **options):
    """A GGX table baked with `options`, lossless, and opened from its file."""
    out = str(tmp_path / f"{name}.btdb")
    brdftab.bake(GGX, out, codec="f32", **options)
    return out, brdftab.open(out)


def test_own_values_save_and_open_as_the_original(tmp_path):
    out, b = baked(tmp_path, "t", preset="small")
    t = b.table()
    same = t.with_values(t.values)
    np.testing.assert_array_equal(same.values, t.values)
    assert same.grid["stored_shape"] == t.grid["stored_shape"]
    f = b.eval(WI, WO)
    assert (f > 0).all()
    np.testing.assert_array_equal(same.open().eval(WI, WO), f)
    info = same.save(tmp_path / "back.btdb", codec="f32")
    entry = info["tables"][0]
    assert entry["name"] == "back" and entry["values"] == t.values.size
    assert entry["codec"]["quant"] == "f32"
    assert entry["source"]["description"].startswith("values from Python on the grid of")
    assert info == brdftab.info(str(tmp_path / "back.btdb"))
    np.testing.assert_array_equal(brdftab.open(tmp_path / "back.btdb").eval(WI, WO), f)
    # Into a database: an existing name needs replace=True.
    db = str(tmp_path / "lib.btdb")
    same.save(f"{db}#a")
    with pytest.raises(brdftab.Error, match="already holds"):
        same.save(f"{db}#a")
    info = same.save(f"{db}#a", replace=True, codec="f32")
    assert info["tables"][0]["name"] == "a"
    np.testing.assert_array_equal(brdftab.open(f"{db}#a").eval(WI, WO), f)
    # Beside DB#NAME, `name` may only repeat NAME, as in `bake`: save(f"{db}#b", name="c")
    # wrote table b and dropped c without a word.
    with pytest.raises(ValueError, match='"c" conflicts with the output\'s table name "b"'):
        same.save(f"{db}#b", name="c")
    assert brdftab.Database(db).names() == ["a"]
    assert same.save(f"{db}#b", name="b")["tables"][0]["name"] == "b"


@pytest.mark.parametrize("options", [{"preset": "small"}, {"grid": "adaptive:24x12x7"}])
def test_doubled_values_double_every_lookup(tmp_path, options):
    """Every step of a lookup is linear in the values and doubling is exact in floating point:
    lookups double bit for bit (the adaptive table is albedo-calibrated; its factors stay)."""
    _, b = baked(tmp_path, "t", **options)
    t = b.table()
    assert (t.grid.get("calibration") is not None) == ("grid" in options)
    f = b.eval(WI, WO)
    for values in [2 * t.values, (2 * t.values).ravel(), 2 * t.values.astype(np.float64),
                   (2 * t.values).tolist()]:
        doubled = t.with_values(values)
        assert doubled.grid.get("calibration") == t.grid.get("calibration")
        np.testing.assert_array_equal(doubled.open().eval(WI, WO), 2 * f)
    # Strided and Fortran-order arrays are read by their indices, not their memory.
    fortran = np.asfortranarray(2 * t.values)
    np.testing.assert_array_equal(t.with_values(fortran).values, 2 * t.values)
    strided = np.stack([2 * t.values, t.values], axis=-1)[..., 0]
    assert not strided.flags.c_contiguous
    np.testing.assert_array_equal(t.with_values(strided).values, 2 * t.values)


def test_without_the_calibration_a_table_is_the_uncalibrated_bake(tmp_path):
    """The adaptive grid's nodes do not depend on the calibration: the calibrated table without
    its factors is the table baked with calibrate=False, lookup for lookup."""
    _, b = baked(tmp_path, "cal", grid="adaptive:24x12x7")
    _, plain = baked(tmp_path, "plain", grid="adaptive:24x12x7", calibrate=False)
    t, u = b.table(), plain.table()
    assert t.grid.get("calibration") is not None and u.grid.get("calibration") is None
    np.testing.assert_array_equal(t.values, u.values)
    dropped = t.with_values(t.values, calibration=False)
    assert dropped.grid.get("calibration") is None
    g = lambda d: {k: v for k, v in d.items() if k not in ("calibration", "description")}  # noqa: E731
    assert g(dropped.grid) == g(u.grid)
    f, f0 = b.eval(WI, WO), dropped.open().eval(WI, WO)
    np.testing.assert_array_equal(f0, plain.eval(WI, WO))
    ratio = f / f0
    assert np.isfinite(ratio).all() and np.abs(ratio - 1).max() > 1e-3, "factors change lookups"
    # The factors are k_in(θi) k_out(θo), the same for every channel of a grey GGX.
    np.testing.assert_allclose(ratio[:, 1], ratio[:, 0], rtol=1e-6)


def test_a_packed_tables_export_goes_back_in(tmp_path, cli):
    """A packed table (inout, reciprocal) hands out its values flat; the .npy export writes the
    whole rectangle, NaN at the nodes it does not store, and with_values takes either."""
    out, b = baked(tmp_path, "p", grid="16x1x16x32", param="inout",
                   symmetry="isotropic,reciprocal")
    t = b.table()
    assert t.grid["packed"] and t.values.ndim == 1
    npy = str(tmp_path / "p.npy")
    cli("export", out, "--npy", npy)
    rect = np.load(npy)
    assert list(rect.shape) == t.grid["stored_shape"] + [3] and np.isnan(rect).any()
    np.testing.assert_array_equal(t.with_values(rect).values, t.values)
    np.testing.assert_array_equal(t.with_values(2 * rect).open().eval(WI, WO),
                                  2 * b.eval(WI, WO))


def test_bad_values_and_options_are_refused(tmp_path):
    _, b = baked(tmp_path, "t", preset="small")
    t = b.table()
    v = np.array(t.values)
    with pytest.raises(ValueError, match="values"):
        t.with_values(v[:-1])
    with pytest.raises(ValueError, match="values"):
        t.with_values(v.ravel()[:-1])
    with pytest.raises(ValueError, match=r"shape \[.*\] does not fit"):
        t.with_values(v.reshape(v.shape[0], -1))
    for bad in [np.nan, np.inf, -np.inf]:
        w = v.copy()
        w[1, 0, 2, 3, 1] = bad
        with pytest.raises(ValueError, match=r"values\[1, 0, 2, 3, 1\] is"):
            t.with_values(w)
    with pytest.raises(ValueError, match="values"), np.errstate(over="ignore"):
        t.with_values(np.full(v.shape, 1e300))  # beyond float32: infinite
    with pytest.raises(TypeError, match="values"):
        t.with_values("not numbers")
    with pytest.raises(TypeError, match="values"):
        t.with_values(v.astype(np.complex64))
    with pytest.raises(ValueError, match="masked"):
        t.with_values(np.ma.masked_less(v, 0.5))
    with pytest.raises(ValueError, match="codec"):
        t.save(tmp_path / "x.btdb", codec="zip")
    with pytest.raises(ValueError, match="name"):
        t.save(tmp_path / "x.btdb", name="a#b")
    with pytest.raises(TypeError, match="unexpected keyword"):
        t.save(tmp_path / "x.btdb", preset="small")
    with pytest.raises(brdftab.Error, match="encode"):
        t.with_values(np.full(v.shape, 1e6)).save(tmp_path / "x.btdb", codec="f16")
    assert not (tmp_path / "x.btdb").exists()
    # Negative values are kept (unmeasured nodes of an f_r table, read as 0).
    w = v.copy()
    w[0, 0, 0, 0, 0] = -1.0
    assert t.with_values(w).values[0, 0, 0, 0, 0] == -1.0


def test_an_in_memory_brdf_has_no_source_to_reopen(tmp_path):
    _, b = baked(tmp_path, "t", preset="small")
    t = b.table()
    m = t.open(interp="nearest")
    assert m.interp == "nearest" and m.source.startswith("<in-memory table")
    np.testing.assert_array_equal(m.table().values, t.values)
    with pytest.raises(TypeError, match="pickle"):
        pickle.dumps(m)
    with pytest.raises(brdftab.Error, match="in-memory"):
        m.table(preset="small")
    with pytest.raises(ValueError, match="interp"):
        t.open(interp="cubic")


@pytest.mark.parametrize("options", [dict(preset="small"),
                                     dict(grid="6x1x6x12", param="inout", symmetry="all")])
def test_node_directions_are_where_the_bake_sampled(options):
    """`node_angles` and `node_directions` name every stored node in the layout of `values`
    (a packed inout table: flat): a table baked in memory (no codec) holds the source's own
    f_r at each node whose directions are both above the horizon, bit for bit; the angles
    are the parameterization's of those directions."""
    src = brdftab.open(GGX)
    t = src.table(**options)
    a = t.node_angles()
    wi, wo = t.node_directions()
    v = t.values.reshape(-1, 3)
    assert a.shape[-1] == 4 and wi.shape == wo.shape == a.shape[:-1] + (3,)
    assert a.shape[:-1] == (t.values.shape[:-1] if t.values.ndim > 1 else (v.shape[0],))
    wi, wo, a = wi.reshape(-1, 3), wo.reshape(-1, 3), a.reshape(-1, 4)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(wo, axis=1), 1, atol=1e-12)
    inside = (wi[:, 2] > 1e-3) & (wo[:, 2] > 1e-3)
    assert inside.sum() > len(inside) // 3
    np.testing.assert_array_equal(src.eval(wi[inside], wo[inside]), v[inside])
    # A source evaluated at the nodes goes back in as it comes out, (nodes, c) for a packed
    # table (refused before: only flat or the rectangle were taken), and equals it flat.
    f = src.eval(*t.node_directions())
    assert np.array_equal(t.with_values(f).values, t.with_values(f.reshape(-1)).values)
    assert np.array_equal(t.with_values(f.reshape(-1, 3)).values, t.with_values(f).values)
    if t.grid["param"] == "halfdiff":
        # θh is the angle of wi + wo from the normal, θd the angle of wi from it.
        h = wi + wo
        h /= np.linalg.norm(h, axis=1, keepdims=True)
        np.testing.assert_allclose(np.arccos(np.clip(h[:, 2], -1, 1)), a[:, 0], atol=1e-9)
        np.testing.assert_allclose(np.arccos(np.clip((wi * h).sum(1), -1, 1)), a[:, 2],
                                   atol=1e-9)
    else:
        np.testing.assert_allclose(np.arccos(wi[:, 2]), a[:, 0], atol=1e-9)
        np.testing.assert_allclose(np.arccos(wo[:, 2]), a[:, 2], atol=1e-9)


def test_copies_of_immutable_objects_are_the_objects(tmp_path):
    """`copy.copy`/`deepcopy` of a `Brdf` reopened its source from disk (an in-memory table's
    raised "cannot pickle"), of a `Table` raised "cannot pickle": both are immutable, so a copy
    is the object itself, as for a tuple; a container of them deep-copies."""
    import copy

    path = tmp_path / "g.btdb"
    brdftab.bake(GGX, path, preset="small")
    b = brdftab.open(path)
    t = b.table()
    m = t.open()
    for x in (b, t, m):
        assert copy.copy(x) is x and copy.deepcopy(x) is x
    d = copy.deepcopy({"brdf": b, "table": t, "memory": m})
    assert d["brdf"] is b and d["table"] is t and d["memory"] is m
    path.unlink()  # nothing is reopened
    assert copy.deepcopy(b) is b
    with pytest.raises(TypeError, match="pickle"):
        pickle.dumps(m)
