"""The Python API against the CLI, the published RGL reference values, and its own contract."""

import json
import multiprocessing
import os
import pathlib
import pickle
import shutil
import subprocess
import sys

import numpy as np
import pytest

import brdftab

LAMBERT = '{"model": "lambert", "kd": [0.1, 0.2, 0.3]}'
GGX = '{"model": "ggx", "alpha": 0.3, "ks": 0.8}'


def upper(n, seed=0):
    """n random directions of the upper hemisphere (not normalized)."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return v


def numbers(text):
    return np.array([[float(x) for x in line.split()] for line in text.strip().splitlines()])


def pairs_text(wi, wo):
    return "".join(" ".join(repr(float(x)) for x in (*a, *b)) + "\n" for a, b in zip(wi, wo))


# ---- evaluation ----------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["spec", "rgl"])
def test_eval_matches_cli(kind, cli, paper):
    src = GGX if kind == "spec" else paper
    b = brdftab.open(src)
    wi, wo = upper(200, 1), upper(200, 2)
    got = b.eval(wi, wo)
    assert got.dtype == np.float32 and got.shape == (200, 3)
    want = numbers(cli("eval", src, stdin=pairs_text(wi, wo)))
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-30)


def test_pdf_and_sample_match_cli(cli):
    b = brdftab.open(GGX)
    wo = np.array([0.3, -0.2, 0.9])
    u = np.random.default_rng(3).random((500, 2))
    wi, pdf, w = b.sample(wo, u)
    assert wi.shape == (500, 3) and pdf.shape == (500,) and w.shape == (500, 3)
    assert wi.dtype == np.float64 and pdf.dtype == np.float64 and w.dtype == np.float32
    ok = pdf > 0
    assert ok.mean() > 0.9
    # pdf: the Python value, the CLI's, and the one sample() returned agree.
    wos = np.tile(wo, (ok.sum(), 1))
    cli_pdf = numbers(cli("pdf", GGX, stdin=pairs_text(wi[ok], wos)))[:, 0]
    np.testing.assert_allclose(b.pdf(wi[ok], wos), cli_pdf, rtol=1e-9)
    np.testing.assert_allclose(pdf[ok], cli_pdf, rtol=1e-6)
    # weight = f cos θi / pdf (brdftab sample's convention)
    f = b.eval(wi[ok], wos)
    cos_i = wi[ok][:, 2] / np.linalg.norm(wi[ok], axis=1)
    np.testing.assert_allclose(w[ok], f * (cos_i / pdf[ok])[:, None], rtol=1e-4)


def test_sample_at_wavelengths_and_its_delta_flags():
    """`sample(wo, u, nm=..., delta=True)`: the same draws as `sample(wo, u)`; smooth draws
    weighted by `eval_spectral` at nm, a mirror term's draws by its Fresnel term there (for a
    spectral source at its own wavelengths: `sample`'s weights), and flagged as delta draws."""
    lam = [420.0, 530.0, 650.0]
    spec = json.dumps({"model": "sum", "terms": [
        {"model": "ggx", "alpha": 0.3, "fresnel": {"conductor": "Cu"}},
        {"model": "mirror", "fresnel": {"conductor": "Au"}}]})
    wo = upper(400, 5)
    u = np.random.default_rng(6).random((400, 2))
    for b in (brdftab.open(spec), brdftab.open(spec, wavelengths=lam)):
        wi, pdf, w = b.sample(wo, u)
        wi2, pdf2, w2, delta = b.sample(wo, u, nm=lam, delta=True)
        assert w2.shape == (400, 3) and delta.dtype == np.bool_
        np.testing.assert_array_equal(wi, wi2)
        np.testing.assert_array_equal(pdf, pdf2)
        assert 0 < delta.sum() < 400
        # delta draws: the mirror direction, a choice probability, not in pdf()
        mirror = wo[delta] * [-1, -1, 1] / np.linalg.norm(wo[delta], axis=1)[:, None]
        np.testing.assert_allclose(wi[delta], mirror, atol=1e-12)
        assert np.all(pdf[delta] < 1) and np.all(b.pdf(wi[delta], wo[delta]) < pdf[delta] * 1e3)
        smooth = ~delta & (pdf > 0)
        cos_i = wi[smooth, 2]
        want = b.eval_spectral(wi[smooth], wo[smooth], lam) * (cos_i / pdf[smooth])[:, None]
        np.testing.assert_allclose(w2[smooth], want, rtol=1e-5)
        if b.wavelengths:
            np.testing.assert_allclose(w2, w, rtol=1e-5, atol=1e-7)
        else:
            assert not np.allclose(w2[delta], w[delta], rtol=1e-3)  # RGB sits elsewhere
        # one row, and nm per row
        one = b.sample(wo[0], u[0], nm=lam, delta=True)
        assert one[2].shape == (3,) and one[3].shape == ()
        per_row = b.sample(wo, u, nm=np.tile(lam, (400, 1)))
        np.testing.assert_array_equal(per_row[2], w2)
        # no wavelengths (k = 0), one set or one per row: the same draws, empty weights (per
        # row they were all (0, 0, 0) with pdf 0)
        for nm in (np.zeros(0), np.zeros((400, 0))):
            wi0, pdf0, w0, d0 = b.sample(wo, u, nm=nm, delta=True)
            assert w0.shape == (400, 0)
            np.testing.assert_array_equal(wi0, wi)
            np.testing.assert_array_equal(pdf0, pdf)
            np.testing.assert_array_equal(d0, delta)
    with pytest.raises(ValueError, match="nm"):
        b.sample(wo, u, nm=[500.0, float("nan")])
    with pytest.raises(ValueError, match="nm"):
        b.sample(wo, u, nm=np.ones((3, 2)))


def test_rgl_matches_published_reference(rgl):
    """rgl-epfl/brdf-loader's values (f_r cos θo) for the seven files, as tests/rgl_reference.rs."""
    rows = [l.split("\t") for l in (rgl / "reference_eval_powitacq_rgb.tsv").read_text().splitlines()[1:]]
    by_file = {}
    for r in rows:
        by_file.setdefault(r[0], []).append([float(x) for x in r[1:]])
    for file, vals in by_file.items():
        v = np.array(vals)
        v = v[v[:, 0] > 0]  # the pole θi = 0 has an undefined azimuth (see the Rust test)
        ti, pi, to, po = np.radians(v[:, :4]).T
        sph = lambda t, p: np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], 1)
        got = brdftab.open(str(rgl / file)).eval(sph(ti, pi), sph(to, po))
        want = v[:, 4:] / np.cos(to)[:, None]
        rel = np.abs(got - want) / np.maximum(np.abs(want), 1e-6)
        assert rel.max() < 1e-4, (file, rel.max())


def test_shapes_and_broadcast():
    b = brdftab.open(LAMBERT)
    one = b.eval([0, 0, 1], [0.3, 0, 1])
    assert one.shape == (3,) and one.dtype == np.float32
    np.testing.assert_allclose(one, [0.1, 0.2, 0.3], rtol=1e-7)
    assert b.eval(upper(7), [0, 0, 1]).shape == (7, 3)
    assert b.eval([0, 0, 1], upper(7)).shape == (7, 3)
    assert b.eval(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0, 3)
    assert b.pdf([0, 0, 1], [0, 0, 1]).shape == ()
    assert b.pdf(upper(4), upper(4)).shape == (4,)
    # below the horizon: 0
    assert b.eval([0, 0, -1], [0, 0, 1]).tolist() == [0, 0, 0]
    # lists, tuples, float32 and int arrays are accepted; non-contiguous views too
    assert b.eval(((0, 0, 1),), np.array([[0, 0, 1]], dtype=np.float32)).shape == (1, 3)
    assert b.eval(np.array([0, 0, 2]), [0, 0, 1]).shape == (3,)
    wi = upper(10)[::2]
    np.testing.assert_array_equal(b.eval(wi, wi), b.eval(wi.copy(), wi.copy()))
    wi, pdf, w = b.sample([0, 0, 1], [0.5, 0.5])
    assert wi.shape == (3,) and pdf.shape == () and w.shape == (3,)


def test_large_batch_is_consistent(paper):
    b = brdftab.open(paper)
    wi, wo = upper(50_000, 5), upper(50_000, 6)
    big = b.eval(wi, wo)
    np.testing.assert_array_equal(big[:100], b.eval(wi[:100], wo[:100]))
    np.testing.assert_array_equal(big[-1], b.eval(wi[-1], wo[-1]))


def test_channels_flags_wavelengths(paper):
    b = brdftab.open(LAMBERT)
    assert b.channels == ["R", "G", "B"]
    assert b.flags == {"delta": False, "reciprocal": True, "isotropic": True,
                       "bilateral": True, "transmission": False,
                       "lobes": {"diffuse": True, "glossy": False, "delta": False}}
    assert brdftab.open(GGX).flags["lobes"] == {"diffuse": False, "glossy": True, "delta": False}
    s = brdftab.open(LAMBERT.replace("[0.1, 0.2, 0.3]", "0.5"), wavelengths=[450, 550, 650.5])
    assert s.channels == ["450nm", "550nm", "650.5nm"]
    assert s.wavelengths == [450, 550, 650.5]
    assert s.eval([0, 0, 1], [0, 0, 1]).shape == (3,)
    assert brdftab.open(paper, wavelengths="500,600").channels == ["500nm", "600nm"]
    assert brdftab.open('{"model": "mirror"}').flags["delta"]


def test_albedo():
    b = brdftab.open(LAMBERT)
    a = b.albedo([0.0, 0.5, 1.2])
    assert a.shape == (3, 3)
    np.testing.assert_allclose(a, np.tile(np.array([0.1, 0.2, 0.3]) * np.pi, (3, 1)), rtol=1e-3)
    assert b.albedo(0.3).shape == (3,)


def test_albedo_is_for_light_above_the_horizon():
    """θ′ = π/2 is refused like the CLI's 90°: cos(π/2) in float64 is 6e-17 > 0, so it used to be
    evaluated as a light just above the horizon, and Ward's albedo (which diverges there) came
    out as 3.5e5."""
    ward = brdftab.open('{"model": "ward", "ks": 0.1, "alpha_x": 0.2, "alpha_y": 0.2}')
    for t in [np.pi / 2, np.radians(90.0)]:
        with pytest.raises(ValueError, match="theta.*above the horizon"):
            ward.albedo([0.0, t])
    assert np.isfinite(ward.albedo(np.nextafter(np.pi / 2, 0))).all()


def test_albedo_of_an_anisotropic_model_takes_the_lights_azimuth():
    """`albedo(theta)` was the albedo of light from azimuth 0 only, with no way to ask for
    another and no word of it: GGX with α = (0.01, 1) reflects 0.517 at θ′ = 89° from φ′ = 0
    but 0.904 from φ′ = 0.3. Light at φ′ = π/2 on (α_x, α_y) is light at φ′ = 0 on (α_y, α_x)
    (the model turned by a quarter about the normal), each integral to 1e-6."""
    spec = '{{"model": "ggx", "alpha_x": {}, "alpha_y": {}}}'
    b, turned = brdftab.open(spec.format(0.01, 1.0)), brdftab.open(spec.format(1.0, 0.01))
    theta = np.radians([0.0, 45.0, 80.0, 89.0])
    np.testing.assert_allclose(b.albedo(theta, phi=np.pi / 2), turned.albedo(theta), rtol=5e-6)
    np.testing.assert_allclose(b.albedo(theta), b.albedo(theta, 0.0), rtol=0)
    at89 = b.albedo(np.radians(89.0), phi=0.3)[0]
    assert abs(at89 - 0.904) < 0.002, at89  # the Mitsuba-drawn estimate: 0.9041 ± 0.0002
    assert abs(b.albedo(np.radians(89.0))[0] - 0.5175) < 0.002
    for phi in [np.nan, np.inf]:
        with pytest.raises(ValueError, match="phi"):
            b.albedo([], phi=phi)


def test_albedo_matches_cli(cli):
    b = brdftab.open(GGX)
    got = b.albedo(np.radians([0, 30, 60]))
    want = numbers(cli("albedo", GGX, "--theta", "0,30,60"))[:, 1:]
    np.testing.assert_allclose(got, want, rtol=1e-6)


# ---- check, bake, convert, databases, fit --------------------------------------------------

def test_check_is_cli_json(cli):
    got = brdftab.check(GGX)
    want = json.loads(cli("check", GGX, "--json"))
    assert got.keys() == want.keys()
    assert got == want


def test_bake_returns_info(tmp_path, cli):
    out = str(tmp_path / "ggx.btdb")
    info = brdftab.bake(GGX, out, preset="small", codec="log16", codec_tolerance=1e-3)
    assert info == json.loads(cli("info", out, "--json"))
    (t,) = info["tables"]
    assert t["name"] == "ggx" and t["parameterization"] == "halfdiff"
    table = brdftab.open(out)
    rel = np.abs(table.eval(upper(100), upper(100, 9)) - brdftab.open(GGX).eval(upper(100), upper(100, 9)))
    assert np.isfinite(rel).all()
    # grid sizes, inout, explicit symmetry, another name
    info = brdftab.bake(LAMBERT, out, grid="8x1x8x16", param="inout", symmetry="isotropic",
                        name="tiny", codec="f32")
    assert info["tables"][0]["name"] == "tiny"
    assert info["tables"][0]["parameterization"] == "inout"


def test_info_names_what_the_values_are(tmp_path):
    # Ward's table stores f_r cos θi cos θo: Table.values are that, and info says so.
    out = str(tmp_path / "ward.btdb")
    ward = '{"model": "ward", "ks": 0.5, "alpha_x": 0.1, "alpha_y": 0.3}'
    (t,) = brdftab.bake(ward, out, preset="small")["tables"]
    assert (t["quantity"], t["calibrated"]) == ("fr_cos_cos", False)
    (t,) = brdftab.bake(GGX, out, preset="small")["tables"]
    assert (t["quantity"], t["calibrated"]) == ("fr", False)


def test_bake_target_error_matches_the_cli(tmp_path, cli):
    # the same request from Python and the CLI picks the same adaptive grid
    a, b = str(tmp_path / "a.btdb"), str(tmp_path / "b.btdb")
    info = brdftab.bake(GGX, a, target_error=0.01)
    cli("bake", GGX, "-o", b, "--target-error", "1%")
    (ta,), (tb,) = info["tables"], json.loads(cli("info", b, "--json"))["tables"]
    assert ta["shape"] == tb["shape"]
    with pytest.raises((brdftab.Error, ValueError), match="target_error"):
        brdftab.bake(GGX, a, preset="small", target_error=0.01)
    # a bad value names its field once (it was "invalid argument `target_error`: invalid
    # argument `target_error`: ...")
    with pytest.raises((brdftab.Error, ValueError)) as e:
        brdftab.bake(GGX, a, target_error=-1)
    assert str(e.value).count("target_error") == 1, str(e.value)


def test_paths_may_be_pathlike(tmp_path, paper):
    # Sources and outputs are str or os.PathLike (a pathlib.Path was a TypeError).
    out = tmp_path / "lam.btdb"
    info = brdftab.bake(LAMBERT, out, preset="small")
    assert info == brdftab.info(out) == brdftab.info(str(out))
    wi, wo = upper(50, 3), upper(50, 4)
    assert np.array_equal(brdftab.open(out).eval(wi, wo), brdftab.open(str(out)).eval(wi, wo))
    assert brdftab.check(out)["positive"]
    conv = brdftab.convert(pathlib.Path(paper), tmp_path / "p.btdb", preset="small")
    assert conv["format"] == "table" and (tmp_path / "p.btdb").exists()
    with pytest.raises(TypeError, match="source"):
        brdftab.open(42)
    # bytes, and an os.PathLike of bytes, are paths as os.fspath gives them (session 41: they
    # were a TypeError)
    for p in [paper.encode(), _BytesPath(paper)]:
        assert np.array_equal(brdftab.open(p).eval(wi, wo), brdftab.open(paper).eval(wi, wo))


def test_a_source_whose_name_is_not_utf8(tmp_path):
    """A file name of bytes that are not UTF-8 — as bytes, as a str of surrogate escapes
    (`os.fsdecode`), as a pathlib.Path — opens, bakes and converts, and pickles (session 41: a
    ValueError "not valid UTF-8"). Its `Brdf.source` is the `os.fsdecode` str; a missing one is
    an error naming it lossily."""
    raw = os.fsencode(tmp_path) + b"/caf\xe9.btdb"
    brdftab.bake(LAMBERT, tmp_path / "t.btdb", preset="small")
    os.rename(tmp_path / "t.btdb", raw)
    wi, wo = upper(20, 5), upper(20, 6)
    want = brdftab.open(LAMBERT).eval(wi, wo)
    for p in [raw, os.fsdecode(raw), pathlib.Path(os.fsdecode(raw))]:
        b = brdftab.open(p)
        assert b.source == os.fsdecode(raw)
        # a constant stored by log16: within its 1e-3
        np.testing.assert_allclose(b.eval(wi, wo), want, rtol=1e-3)
        np.testing.assert_array_equal(pickle.loads(pickle.dumps(b)).eval(wi, wo), b.eval(wi, wo))
    out = tmp_path / "again.btdb"
    brdftab.bake(raw, out, preset="small")
    np.testing.assert_allclose(brdftab.open(out).eval(wi, wo), want, rtol=2e-3)
    conv = brdftab.convert(os.fsdecode(raw), f"{tmp_path}/lib.btdb#m", pairs=0)
    assert conv["format"] == "table"
    np.testing.assert_allclose(brdftab.open(f"{tmp_path}/lib.btdb#m").eval(wi, wo), want,
                               rtol=2e-3)
    with pytest.raises(brdftab.Error, match="caf\ufffd-missing.btdb"):
        brdftab.open(os.fsencode(tmp_path) + b"/caf\xe9-missing.btdb")


def test_every_path_may_be_bytes_that_are_not_utf8(tmp_path):
    """Every path argument — bake's and convert's OUTPUT (a file and DB#NAME), Table.save's,
    info's SOURCE, bake_cached's cache_dir, a Database's path and every method of it — takes a
    name that is not UTF-8, as bytes, a str of surrogate escapes (os.fsdecode) or a pathlib.Path
    (before session 42: ValueError "not valid UTF-8" for the str, TypeError for bytes). Every
    path it hands back — bake_cached's "path", Database.path and .source, and the "file" and
    "output" of the report dicts (before session 43: the lossy U+FFFD text, which does not
    open) — is os.fsdecode's str; only error messages show the name lossily."""
    d = os.fsencode(tmp_path) + b"/caf\xe9"
    os.mkdir(d)
    wi, wo = upper(20, 7), upper(20, 8)
    want = brdftab.open(LAMBERT).eval(wi, wo)
    forms = {"bytes": lambda b: b, "str": os.fsdecode,
             "path": lambda b: pathlib.Path(os.fsdecode(b))}
    for k, form in forms.items():
        f = d + f"/{k}".encode()
        # bake and convert to a file and to DB#NAME; info of each
        info = brdftab.bake(LAMBERT, form(f + b".btdb"), preset="small")
        assert info["file"] == os.fsdecode(f + b".btdb")
        assert brdftab.open(info["file"]).eval(wi, wo).shape == want.shape
        for out in [f + b".btdb", f + b"-lib.btdb#m"]:
            if out.endswith(b"#m"):
                c = brdftab.convert(form(f + b".btdb"), form(out), pairs=0)
                assert c["output"] == os.fsdecode(out) and c["info"]["file"] == \
                    os.fsdecode(f + b"-lib.btdb")
            np.testing.assert_allclose(brdftab.open(out).eval(wi, wo), want, rtol=2.1e-3)
            got = brdftab.info(form(out))
            assert got["file"] == os.fsdecode(f + (b"-lib.btdb" if b"#" in out else b".btdb"))
            assert len(got["tables"]) == 1
        conv = brdftab.convert(LAMBERT, form(f + b".bsdf"), resolution=8, theta_i=3, phi_i=1,
                               pairs=0)
        assert conv["output"] == os.fsdecode(f + b".bsdf")
        assert brdftab.info(conv["output"])["format"] == "rgl"
        assert brdftab.info(form(f + b".bsdf"))["format"] == "rgl"
        # Table.save
        t = brdftab.open(f + b".btdb").table()
        assert t.save(form(f + b"-saved.btdb"), codec="f32")["file"] == \
            os.fsdecode(f + b"-saved.btdb")
        np.testing.assert_array_equal(brdftab.open(f + b"-saved.btdb").eval(wi, wo),
                                      brdftab.open(f + b".btdb").eval(wi, wo))
        # a Database and every method of it
        db = brdftab.Database(form(f + b"-db.btdb"))
        assert db.path == os.fsdecode(f + b"-db.btdb") and len(db) == 0
        db.add(LAMBERT, "a", preset="small")
        with open(f + b".btdb", "rb") as fh:
            db.add_bytes("b", fh.read())
        db.rename("a", "c")
        assert db.names() == ["c", "b"] and "c" in db and list(db) == ["c", "b"]
        np.testing.assert_allclose(db.open("c").eval(wi, wo), want, rtol=2.1e-3)
        assert brdftab.open(db.source("b")).eval(wi, wo).tolist() == \
            brdftab.open(f + b".btdb").eval(wi, wo).tolist()
        assert db.info()["file"] == os.fsdecode(f + b"-db.btdb")
        db.remove("c")
        assert db.names() == ["b"]
        # bake_cached in such a directory: the path it gives opens
        c = brdftab.bake_cached(form(f + b".btdb"), cache_dir=form(f + b"-cache"), preset="small")
        assert c["path"].startswith(os.fsdecode(f + b"-cache/")) and not c["hit"]
        np.testing.assert_allclose(brdftab.open(c["path"]).eval(wi, wo), want, rtol=2.1e-3)
        again = brdftab.bake_cached(form(f + b".btdb"), form(f + b"-cache"), preset="small")
        assert again == {"path": c["path"], "hit": True}
    with pytest.raises(brdftab.Error, match="caf\ufffd/none.btdb"):
        brdftab.info(d + b"/none.btdb")


def test_info_describes_measured_files_as_the_cli_does(cli, paper):
    """brdftab.info on an RGL file: the CLI's `info --json` (it used to raise "wrong magic")."""
    got = brdftab.info(paper)
    assert got["format"] == "rgl" and got["description"] == "White A4 paper (160 gsm)"
    assert json.loads(cli("info", paper, "--json")) == got


class _BytesPath:
    """An os.PathLike whose path is bytes (any path argument may be one)."""

    def __init__(self, p):
        self.p = str(p).encode()

    def __fspath__(self):
        return self.p


def test_database(tmp_path):
    db = brdftab.Database(tmp_path / "m.btdb")
    assert "matte" not in db  # a database not created yet holds no table
    assert not (tmp_path / "m.btdb").exists()
    db.add(LAMBERT, "matte", preset="small")
    db.add(GGX, "shiny", preset="small")
    assert db.names() == ["matte", "shiny"] and "matte" in db
    with pytest.raises((brdftab.Error, ValueError), match="shiny"):
        db.add(GGX, "shiny", preset="small")
    db.add(GGX, "shiny", preset="small", replace=True)
    m = db.open("matte", interp="nearest")
    assert m.interp == "nearest"
    np.testing.assert_allclose(m.eval([0, 0, 1], [0, 0, 1]), [0.1, 0.2, 0.3], rtol=2e-3)
    assert len(db.info()["tables"]) == 2
    db.remove("matte")
    assert db.names() == ["shiny"]
    with pytest.raises(brdftab.Error):
        db.remove("matte")
    with pytest.raises(brdftab.Error):
        db.open("matte")
    with pytest.raises(ValueError):
        db.add(LAMBERT, "a#b")
    with pytest.raises(ValueError, match="name"):  # the name's rule, as add and open apply it
        db.remove("a#b")
    assert pickle.loads(pickle.dumps(db)).names() == ["shiny"]
    # A handle on a path, as pathlib.Path: a pickled copy, or another handle on the same path,
    # is equal (they were unequal: identity) and hashes alike.
    same = pickle.loads(pickle.dumps(db))
    assert same == db == brdftab.Database(str(tmp_path / "m.btdb")) and hash(same) == hash(db)
    assert db != brdftab.Database(tmp_path / "other.btdb") and db != str(tmp_path / "m.btdb")


def test_database_rename(tmp_path):
    """`Database.rename(old, new)` (session 41): the table keeps its place and its values; a
    taken or missing name is a brdftab.Error naming the database, a bad name a ValueError."""
    db = brdftab.Database(tmp_path / "m.btdb")
    db.add(LAMBERT, "matte", preset="small")
    db.add(GGX, "shiny", preset="small")
    before = db.open("matte").eval([0, 0, 1], [0.6, 0, 0.8])
    db.rename("matte", "chalk")
    assert db.names() == ["chalk", "shiny"]
    np.testing.assert_array_equal(db.open("chalk").eval([0, 0, 1], [0.6, 0, 0.8]), before)
    with pytest.raises(brdftab.Error, match=r"m\.btdb already holds a table `shiny`"):
        db.rename("chalk", "shiny")
    with pytest.raises(brdftab.Error, match=r"table `matte` in .*m\.btdb"):
        db.rename("matte", "x")
    with pytest.raises(ValueError, match="name"):
        db.rename("chalk", "a/b")
    with pytest.raises(brdftab.Error, match="none.btdb"):
        brdftab.Database(tmp_path / "none.btdb").rename("a", "b")
    assert db.names() == ["chalk", "shiny"]


def test_a_database_has_a_length_and_iterates_over_its_names(tmp_path):
    """`len(db)` and `for name in db` are the tables, as `names()` lists them (a Database had
    `in` but neither); a database not created yet holds none, as `in` says."""
    db = brdftab.Database(tmp_path / "m.btdb")
    assert len(db) == 0 and list(db) == [] and not db
    db.add(LAMBERT, "matte", preset="small")
    db.add(GGX, "shiny", preset="small")
    assert len(db) == 2 and list(db) == ["matte", "shiny"] == db.names()
    assert [db.open(n).source for n in db] == [db.source("matte"), db.source("shiny")]
    db.remove("matte")
    assert len(db) == 1 and list(db) == ["shiny"]


def test_a_database_path_is_a_str_bytes_or_a_pathlike(tmp_path, monkeypatch):
    """Database(path) took str(path) of anything: Database(b"m.btdb").add(...) wrote a file
    named "b'm.btdb'", Database(3) a file "3". Now it refuses what `open` and `bake` refuse,
    naming the argument, and takes what they take (bytes since session 42: the path as
    os.fsdecode gives it); and `source(name)` checks the name as add, open and remove do."""
    monkeypatch.chdir(tmp_path)
    for bad in [3, None, 1.5]:
        with pytest.raises(TypeError, match="path: expected a str, bytes or an os.PathLike"):
            brdftab.Database(bad).add(LAMBERT, "a", preset="small")
    assert not list(tmp_path.iterdir())
    for p in [pathlib.Path("m.btdb"), b"m.btdb", _BytesPath("m.btdb"), "m.btdb"]:
        assert brdftab.Database(p).path == "m.btdb"
    with pytest.raises(ValueError, match="name"):
        brdftab.Database("m.btdb").source("a#b")
    with pytest.raises(TypeError, match="name"):
        brdftab.Database("m.btdb").source(3)


def test_table_names_follow_the_librarys_rule(tmp_path):
    """An empty name, `DB#` with nothing after the `#`, and names with control characters were
    stored as given (a table named "\\0", a file named `n.btdb#`); the library's one rule
    refuses them, naming the field."""
    db = brdftab.Database(tmp_path / "n.btdb")
    for name in ["", "\0", "a\tb", "red\x1b[0m", "a/b", "a#b", "a\\b"]:
        with pytest.raises(ValueError, match="name"):
            db.add(LAMBERT, name, preset="small")
        with pytest.raises(ValueError, match="name"):
            brdftab.bake(LAMBERT, tmp_path / "n.btdb", preset="small", name=name)
    with pytest.raises(ValueError, match="output"):
        brdftab.bake(LAMBERT, f"{tmp_path}/n.btdb#", preset="small")
    with pytest.raises(ValueError, match="output"):
        brdftab.bake(LAMBERT, f"{tmp_path}/n.btdb#a\nb", preset="small")
    assert not list(tmp_path.iterdir())
    # `x.btdb#` names no table; a file of that name, when one exists, is read as that file.
    with pytest.raises(ValueError, match="source"):
        brdftab.open(f"{tmp_path}/x.btdb#")
    (tmp_path / "x.btdb#").write_bytes(b"")
    with pytest.raises(brdftab.Error, match="not a file brdftab can read"):
        brdftab.open(f"{tmp_path}/x.btdb#")
    db.add(LAMBERT, "ok", preset="small")
    assert db.names() == ["ok"]


def test_a_file_with_a_hash_in_its_name_opens_as_that_file(tmp_path):
    """`a#b.btdb` was split as DB#NAME (table `b.btdb` of a database `a`) and could not be
    opened; a string that names an existing file is that file, else DB#NAME as before."""
    brdftab.bake(LAMBERT, tmp_path / "plain.btdb", preset="small")
    (tmp_path / "scan#2").mkdir()
    want = brdftab.open(tmp_path / "plain.btdb").eval([0, 0, 1], [0, 0, 1])
    for f in ["a#b.btdb", "scan#2/x#y.btdb"]:
        shutil.copy(tmp_path / "plain.btdb", tmp_path / f)
        np.testing.assert_array_equal(brdftab.open(tmp_path / f).eval([0, 0, 1], [0, 0, 1]), want)
        np.testing.assert_array_equal(brdftab.open(str(tmp_path / f)).eval([0, 0, 1], [0, 0, 1]), want)
    db = brdftab.Database(tmp_path / "lib.btdb")
    db.add(LAMBERT, "m", preset="small")
    assert brdftab.open(f"{tmp_path}/lib.btdb#m").channels == ["R", "G", "B"]


def test_convert(tmp_path, paper):
    r = brdftab.convert(paper, str(tmp_path / "rgl.btdb"), preset="small", pairs=2000)
    assert r["output"].endswith("#paper_white_rgb")
    assert r["accuracy"]["pairs"] == 2000 and r["accuracy"]["rel_rmse_80"] < 0.1
    assert r["info"]["tables"][0]["name"] == "paper_white_rgb"
    merl = str(tmp_path / "lambert.binary")
    brdftab.convert(LAMBERT, merl)
    np.testing.assert_allclose(brdftab.open(merl).eval([0, 0.1, 1], [0.2, 0, 1]), [0.1, 0.2, 0.3], rtol=1e-3)


def test_convert_writes_bsdf_like_the_cli(tmp_path, cli):
    # one request layer: Python's convert writes the same .bsdf file as the CLI's
    a, b = str(tmp_path / "a.bsdf"), str(tmp_path / "b.bsdf")
    r = brdftab.convert(LAMBERT, a, theta_i=4, resolution=16, ndf_resolution=32, pairs=500)
    cli("convert", LAMBERT, b, "--theta-i", "4", "--resolution", "16", "--ndf-resolution", "32",
        "--pairs", "500")
    assert r["format"] == "rgl" and r["theta_i"] == 4 and r["resolution"] == 16
    assert r["error"]["pairs"] == 500
    # Beside the figure within 80°, the whole hemisphere, the grazing band and the albedo.
    e = r["error"]
    assert 0 <= e["rel_rmse"] and e["rel_rmse"] < e["grazing"] and 0 <= e["whole"]
    assert 1 <= e["albedo"]["theta_deg"] <= 89 and e["albedo"]["worst"] >= 0
    assert pathlib.Path(a).read_bytes() == pathlib.Path(b).read_bytes()
    assert brdftab.open(a).channels == ["R", "G", "B"]


def test_interp_is_the_one_lookups_use(tmp_path, paper):
    """`Brdf.interp` says how lookups interpolate, not what was asked: a MERL file reads its
    cells (nearest) unless linear is asked, an RGL file its format's linear warps, a table
    opened at given wavelengths keeps its grid's choice."""
    merl = str(tmp_path / "ggx.binary")
    brdftab.convert(GGX, merl)
    assert brdftab.open(merl).interp == "nearest"
    assert brdftab.open(merl, interp="nearest").interp == "nearest"
    linear = brdftab.open(merl, interp="linear")
    assert linear.interp == "linear"
    # the linear lookup differs from the cell's value between cell centres
    wi, wo = upper(256), upper(256, 1)
    assert not np.array_equal(linear.eval(wi, wo), brdftab.open(merl).eval(wi, wo))
    for asked in ("auto", "nearest", "linear"):
        assert brdftab.open(paper, interp=asked).interp == "linear"
    assert brdftab.open(LAMBERT, interp="nearest").interp == "nearest"  # nothing to interpolate
    spectral = f"{tmp_path}/s.btdb#spectral"
    brdftab.bake(LAMBERT, spectral, preset="small", wavelengths=[450, 550, 650])
    t = brdftab.open(spectral, wavelengths=[450, 550, 650])
    assert t.interp == brdftab.open(spectral).interp == "linear"
    assert brdftab.open(spectral, wavelengths=[450, 550, 650], interp="nearest").interp == "nearest"
    with pytest.raises(brdftab.Error, match="channels"):
        brdftab.open(spectral, wavelengths=[500, 600])


def test_fit_is_cli_json(cli):
    src = '{"model": "lambert", "kd": 0.3}'
    got = brdftab.fit(src, "lambert", pairs=300, starts=2)
    want = json.loads(cli("fit", src, "--model", "lambert", "--json", "--pairs", "300", "--starts", "2"))
    assert got.keys() == want.keys()
    assert got["spec"] == want["spec"]
    np.testing.assert_allclose(got["spec"]["kd"], 0.3, rtol=1e-5)
    g = brdftab.fit(GGX, "ggx", pairs=400, starts=1, params="alpha", log=True)
    assert g["spec"]["model"] == "ggx" and np.isfinite(g["rmse"])


def test_table_values_and_grid(tmp_path):
    out = str(tmp_path / "t.btdb")
    brdftab.bake(GGX, out, preset="small")
    values, grid = brdftab.open(out).table()
    assert values.dtype == np.float32
    assert list(values.shape) == grid["stored_shape"] + [3]
    assert grid["param"] == "halfdiff" and len(grid["stored_axes"]) == 4
    # The keys the docs list are there for defaults too: an f_r table without calibration.
    assert grid["quantity"] == "fr" and grid["calibration"] is None
    v2, g2 = brdftab.open(GGX).table(preset="small")
    np.testing.assert_allclose(v2, values, rtol=2e-3, atol=1e-6)
    # Table.values is a view of the table's memory: no copy per access, read-only, kept alive
    t = brdftab.open(out).table()
    v = t.values
    assert v.base is t and not v.flags.writeable and v.flags.c_contiguous
    assert np.shares_memory(v, t.values)
    with pytest.raises(ValueError):
        v[0, 0, 0, 0, 0] = 1.0
    del t
    assert np.isfinite(v).all()  # the array keeps its table alive


# ---- pickling and workers ------------------------------------------------------------------

def _eval_in_worker(args):
    brdf, wi, wo = args
    return brdf.eval(wi, wo)


def test_pickle_and_multiprocessing(paper):
    b = brdftab.open(paper, interp="nearest")
    c = pickle.loads(pickle.dumps(b))
    # An RGL file is read with its format's own (linear) interpolation whatever was asked.
    assert c.source == paper and c.interp == b.interp == "linear"
    wi, wo = upper(64), upper(64, 1)
    np.testing.assert_array_equal(c.eval(wi, wo), b.eval(wi, wo))
    s = pickle.loads(pickle.dumps(brdftab.open(LAMBERT, wavelengths=[500, 600])))
    assert s.channels == ["500nm", "600nm"]
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        outs = pool.map(_eval_in_worker, [(b, wi[:32], wo[:32]), (b, wi[32:], wo[32:])])
    np.testing.assert_array_equal(np.concatenate(outs), b.eval(wi, wo))


def test_a_pickle_opens_its_file_from_any_working_directory(tmp_path, monkeypatch):
    """A Brdf or Database opened by a relative path pickled that path: a worker in another
    working directory (Dask, Ray) failed with "not found"."""
    (tmp_path / "here").mkdir()
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "here")
    brdftab.bake(LAMBERT, "rel.btdb", preset="small")
    db = brdftab.Database("db.btdb")
    db.add(LAMBERT, "matte", preset="small")
    wi, wo = upper(8), upper(8, 1)
    pickled = [pickle.dumps(brdftab.open(s)) for s in ("rel.btdb", "db.btdb#matte")]
    want = brdftab.open("rel.btdb").eval(wi, wo)
    copy_of_db = pickle.dumps(db)
    # Equal to a handle on the same file by another spelling of its path.
    assert db == brdftab.Database("./db.btdb") == brdftab.Database(str(tmp_path / "here/db.btdb"))
    monkeypatch.chdir(tmp_path / "elsewhere")
    for p in pickled:
        np.testing.assert_array_equal(pickle.loads(p).eval(wi, wo), want)
    assert pickle.loads(copy_of_db).names() == ["matte"]
    # An inline spec stays a spec.
    assert pickle.loads(pickle.dumps(brdftab.open(LAMBERT))).source == LAMBERT


# ---- bad input -----------------------------------------------------------------------------

def test_bad_sources(tmp_path):
    with pytest.raises(brdftab.Error, match="no-such"):
        brdftab.open(str(tmp_path / "no-such.btdb"))
    with pytest.raises(brdftab.Error, match="no-such"):
        brdftab.open(str(tmp_path / "no-such.bsdf"))
    with pytest.raises(brdftab.Error, match="unknown variant `nope`"):
        brdftab.open('{"model": "nope"}')
    with pytest.raises(brdftab.Error, match="invalid"):
        brdftab.open('{"model": "lambert", "kd": -1}')
    junk = tmp_path / "junk.bsdf"
    junk.write_bytes(b"definitely not a tensor file")
    with pytest.raises(brdftab.Error):
        brdftab.open(str(junk))
    with pytest.raises(brdftab.Error):
        brdftab.check(str(tmp_path / "missing.binary"))
    with pytest.raises((brdftab.Error, ValueError), match="no_such_model"):
        brdftab.fit(LAMBERT, "no_such_model")


def test_corrupt_table(tmp_path):
    out = tmp_path / "c.btdb"
    brdftab.bake(GGX, str(out), preset="small")
    data = bytearray(out.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 64] = bytes(64)  # zero a stretch of compressed chunk bytes
    out.write_bytes(bytes(data))
    with pytest.raises(brdftab.Error):
        brdftab.open(str(out))  # eager open checks every chunk
    lazy = brdftab.open(str(out), eager=False)
    with pytest.raises(brdftab.Error):
        lazy.eval(upper(5000), upper(5000, 1))
    out.write_bytes(bytes(data[: len(data) // 3]))  # truncated
    with pytest.raises(brdftab.Error):
        brdftab.open(str(out))


def test_bad_arguments():
    b = brdftab.open(LAMBERT)
    for wi in ([0, 0], [[0, 0, 1, 1]], np.zeros((2, 3, 1)), 1.0):
        with pytest.raises(ValueError, match="shape"):
            b.eval(wi, [0, 0, 1])
    with pytest.raises(ValueError, match="do not broadcast"):
        b.eval(upper(3), upper(4))
    for bad in ([np.nan, 0, 1], [0, np.inf, 1]):  # the NaN rule: 0, not an error
        assert b.eval(bad, [0, 0, 1]).tolist() == [0, 0, 0]
        assert b.pdf([0, 0, 1], bad) == 0
    with pytest.raises(TypeError):
        b.eval(["a", "b", "c"], [0, 0, 1])
    with pytest.raises(TypeError):
        b.eval(np.array([1j, 0, 1]), [0, 0, 1])
    with pytest.raises(TypeError):
        b.eval(None, [0, 0, 1])
    with pytest.raises(ValueError, match=r"\[0, 1\)"):
        b.sample([0, 0, 1], [[0.2, 1.0]])
    with pytest.raises(ValueError, match="shape"):
        b.sample([0, 0, 1], [0.2, 0.3, 0.4])
    with pytest.raises(ValueError):
        b.albedo([2.0])
    with pytest.raises(ValueError, match="interp"):
        brdftab.open(LAMBERT, interp="cubic")
    with pytest.raises(ValueError):
        brdftab.open(LAMBERT, wavelengths=[600, 500])
    with pytest.raises(TypeError):
        brdftab.open(LAMBERT, wavelengths=object())
    with pytest.raises(TypeError, match="unexpected keyword"):
        brdftab.bake(LAMBERT, "/tmp/never.btdb", presett="small")
    with pytest.raises(ValueError):
        brdftab.bake(LAMBERT, "/tmp/never.btdb", grid="1x2x3")
    with pytest.raises(TypeError, match="unexpected keyword"):
        brdftab.fit(LAMBERT, "lambert", colour=True)
    with pytest.raises(TypeError, match="supersample"):
        brdftab.bake(LAMBERT, "/tmp/never.btdb", supersample="two")
    with pytest.raises(ValueError, match="supersample"):
        brdftab.bake(LAMBERT, "/tmp/never.btdb", supersample=65)
    with pytest.raises(ValueError, match="max_theta_deg"):
        brdftab.fit(LAMBERT, "lambert", max_theta_deg=100)
    # A negative node count names its argument (it was an OverflowError "can't convert
    # negative int to unsigned", naming none); numpy integers are counts too.
    for k in ["theta_h", "phi_h", "theta_o", "phi_o"]:
        with pytest.raises(ValueError, match=f"{k}: -1 is not a node count"):
            b.sampling_nodes(**{k: -1})
    assert b.sampling_nodes(theta_h=np.int64(8), phi_h=8, theta_o=4, phi_o=1)["ny"] == 8
    # one-pair evaluation does not leak state between bad and good calls
    assert b.eval([0, 0, 1], [0, 0, 1]).tolist() == pytest.approx([0.1, 0.2, 0.3])


def test_sampling_resolution_doubles_theta_h_for_a_sharp_peak():
    """The library's sampler resolution (what the Mitsuba plugin asks for): 64 × 64 half-vector
    nodes over 32 views for a broad lobe, 128 θh nodes for GGX α = 0.002 (its peak lies within
    the first θh cells of 64), 48 × 48 over 20 × 16 views for an anisotropic source; the nodes
    carry the θh map's constant."""
    broad = brdftab.open('{"model": "ggx", "alpha": 0.3}').sampling_resolution()
    assert broad == {"theta_h": 64, "phi_h": 64, "theta_o": 32, "phi_o": 16}
    sharp = brdftab.open('{"model": "ggx", "alpha": 0.002}')
    res = sharp.sampling_resolution(adjoint=True)
    assert res["theta_h"] == 128 and res["phi_h"] == 64
    nodes = sharp.sampling_nodes(adjoint=True, **res)
    assert nodes["version"] == 3 and nodes["nx"] == 128 and 0.0 < nodes["linear"] < 0.1
    aniso = brdftab.open('{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}')
    assert aniso.sampling_resolution() == {"theta_h": 48, "phi_h": 48, "theta_o": 20, "phi_o": 16}


def test_sampling_resolution_gives_finer_views_to_a_grazing_crescent():
    """A Phong lobe (reciprocal Phong, n = 1000) seen near grazing is a thin crescent in the
    half vector that changes shape between the default 32 views: the library samples it with
    half again the views and the φh nodes (48 and 96), in the nodes the plugin builds too; a
    broad Phong lobe (n = 20) keeps the default."""
    sharp = brdftab.open('{"model": "reciprocal_phong", "ks": 0.5, "n": 1000}')
    res = sharp.sampling_resolution(adjoint=True)
    assert res == {"theta_h": 64, "phi_h": 96, "theta_o": 48, "phi_o": 16}
    nodes = sharp.sampling_nodes(adjoint=True, **res)
    assert (nodes["nx"], nodes["ny"], nodes["nt"]) == (64, 96, 48)
    broad = brdftab.open('{"model": "reciprocal_phong", "ks": 0.5, "n": 20}')
    assert broad.sampling_resolution()["theta_o"] == 32


INTERRUPTED = r"""
import os, signal, sys, threading, time, numpy as np, brdftab
b = brdftab.open(sys.argv[1])
theta = np.linspace(0.0, 1.5, 400)
threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
t0 = time.perf_counter()
try:
    b.albedo(theta)
    print("finished", time.perf_counter() - t0 - 0.5)
except KeyboardInterrupt:
    print("interrupted", time.perf_counter() - t0 - 0.5)
"""


def test_ctrl_c_stops_an_albedo_curve(paper):
    """Ctrl-C (SIGINT) during `albedo` over many angles raises KeyboardInterrupt within about
    one angle's quadrature (each is tenths of a second for measured data; the GIL is taken
    back between 50 ms slices to see the signal). It used to run to the end: 2,000 angles of
    an RGL file, 190 s, Ctrl-C or not (400 angles: KeyboardInterrupt 37 s after the signal)."""
    r = subprocess.run([sys.executable, "-c", INTERRUPTED, paper], capture_output=True,
                       text=True, timeout=600)
    what, after = r.stdout.split()
    assert what == "interrupted", r.stdout + r.stderr
    # One angle of an RGL file takes ~0.1 s on one core: 5 s leaves room for a loaded machine.
    assert float(after) < 5.0, r.stdout


INTERRUPTED_CALL = r"""
import os, signal, sys, threading, time, brdftab
op, rgl, out = sys.argv[1:]
ggx = '{"model": "ggx", "alpha": 0.1}'
call = {
    "bake": lambda: brdftab.bake(ggx, out, preset="large"),
    "bake_cached": lambda: brdftab.bake_cached(ggx, cache_dir=out, preset="large"),
    "convert": lambda: brdftab.convert(ggx, out),
    "fit": lambda: brdftab.fit(rgl, "ggx", starts=8, pairs=200_000),
}[op]
threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
t0 = time.perf_counter()
try:
    call()
    print("finished", time.perf_counter() - t0 - 0.3)
except KeyboardInterrupt:
    print("interrupted", time.perf_counter() - t0 - 0.3)
"""


@pytest.mark.parametrize("op", ["bake", "bake_cached", "convert", "fit"])
def test_ctrl_c_stops_a_bake_a_conversion_and_a_fit(rgl, tmp_path, op):
    """Ctrl-C (SIGINT) during `bake`, `bake_cached`, `convert` or `fit` raises
    KeyboardInterrupt within a second, and a bake or conversion leaves no file. They ran to
    their end with the signal pending (uninterrupted on one machine: the large preset's bake
    3.8 s, the .bsdf conversion 2.5 s, the fit 11 s); now the library is asked to stop
    (`Progress::cancelled`) when the waiting thread, which takes the GIL back every 50 ms,
    sees the signal. Bound: that 50 ms, then one unit of work per thread — a row of a bake's
    values (~1 ms), an incident slice of the .bsdf writer (measured interrupts: up to 0.25 s
    after the signal), an evaluation of the model over the fit's 200,000 pairs (~20 ms) —
    with 4× room for a loaded machine."""
    out = tmp_path / {"bake": "t.btdb", "bake_cached": "cache", "convert": "t.bsdf",
                      "fit": "unused"}[op]
    r = subprocess.run([sys.executable, "-c", INTERRUPTED_CALL, op,
                        str(rgl / "cc_ibiza_sunset_rgb.bsdf"), str(out)],
                       capture_output=True, text=True, timeout=600)
    what, after = r.stdout.split()
    assert what == "interrupted", r.stdout + r.stderr
    assert float(after) < 1.0, r.stdout
    if op == "bake_cached":
        assert not list(out.glob("*.btdb")), list(out.iterdir())
    else:
        assert not out.exists()


def test_sample_checks_u_with_the_gil_released():
    """`sample` reads its `u` rows for the [0, 1)² check with the GIL released, as it draws:
    another thread runs during the whole call. The check held the GIL: 10^7 rows (the last
    outside the square, so the call is the check alone) kept every other Python thread
    waiting for the call's 55–60 ms. Here the other thread's timestamps must span at least
    half of the call (its largest gap was 8–12 ms, Python's switch interval being 5 ms)."""
    import threading
    import time

    b = brdftab.open('{"model": "lambert", "kd": 0.5}')
    n = 10_000_000
    u = np.full((n, 2), 0.5)
    u[-1, 0] = 1.0
    stamps, running, stop = [], threading.Event(), threading.Event()

    def other():
        running.set()
        while not stop.is_set():
            stamps.append(time.perf_counter())

    t = threading.Thread(target=other)
    t.start()
    running.wait()
    try:
        t0 = time.perf_counter()
        with pytest.raises(ValueError, match=f"row {n - 1}"):
            b.sample([0.0, 0.0, 1.0], u)
        t1 = time.perf_counter()
    finally:
        stop.set()
        t.join()
    s = np.array(stamps)
    inside = s[(s > t0) & (s < t1)]
    assert len(inside) > 1 and inside[-1] - inside[0] >= 0.5 * (t1 - t0), (len(inside), t1 - t0)


def elf_sections(path):
    """The section names of an ELF64 little-endian file (the extension module on Linux)."""
    import struct
    with open(path, "rb") as f:
        data = f.read()
    assert data[:4] == b"\x7fELF" and data[4] == 2 and data[5] == 1, "an ELF64 LE file"
    shoff, = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum, shstrndx = struct.unpack_from("<HHH", data, 0x3A)

    def header(i):  # sh_name, sh_offset, sh_size
        name, = struct.unpack_from("<I", data, shoff + i * shentsize)
        offset, size = struct.unpack_from("<QQ", data, shoff + i * shentsize + 0x18)
        return name, offset, size

    _, stroff, strsize = header(shstrndx)
    strtab = data[stroff:stroff + strsize]
    return [strtab[n:strtab.index(b"\0", n)].decode() for n, _, _ in map(header, range(shnum))]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the ELF module (Linux)")
def test_the_installed_extension_carries_no_debug_info():
    """The workspace's release profile keeps debug line tables for profiling; the package does
    not ship them (pyproject's `strip`): before session 43 the installed module was 57 MB, 51 of
    them DWARF, and its wheel 13 MB instead of 2.5."""
    path = brdftab._native.__file__
    names = elf_sections(path)
    assert ".text" in names and ".dynsym" in names, names
    assert not [n for n in names if n.startswith(".debug_")], names
    assert os.path.getsize(path) < 20 << 20, os.path.getsize(path)
