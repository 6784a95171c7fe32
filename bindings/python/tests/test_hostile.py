"""Hostile input through the Python package: fork-started workers, corrupt tables read lazily,
FIFOs as SOURCE, NaN directions, directions of extreme lengths, huge specs. Nothing hangs,
nothing is silently wrong."""

import math
import multiprocessing
import os
import subprocess
import sys

import numpy as np
import pytest

import brdftab

GGX = '{"model": "ggx", "alpha": 0.3, "ks": 0.8}'


def upper(n, seed=0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return v


def _work(args):
    """A worker's batch: large enough (> 4096 pairs) to run on the library's thread pool."""
    brdf, seed = args
    wi, wo = upper(20000, seed), upper(20000, seed + 1)
    u = np.random.default_rng(seed).random((20000, 2))
    f = brdf.eval(wi, wo)
    p = brdf.pdf(wi, wo)
    _, sp, _ = brdf.sample(wo, u)
    return float(f.sum()), float(p.sum()), float(sp.sum())


@pytest.mark.skipif(sys.platform != "linux", reason="fork is the default start method on Linux only")
def test_a_fork_started_pool_after_the_parent_opened_a_table(tmp_path):
    table = tmp_path / "g.btdb"
    brdftab.bake(GGX, str(table), preset="small")
    b = brdftab.open(str(table))  # eager: decodes every chunk on the library's pool
    expected = [_work((b, s)) for s in (1, 2, 3)]  # the parent uses the pool too
    with multiprocessing.get_context("fork").Pool(2) as pool:
        r = pool.map_async(_work, [(b, s) for s in (1, 2, 3)])
        try:
            got = r.get(timeout=120)
        except multiprocessing.TimeoutError:
            pool.terminate()
            pytest.fail("a fork-started worker hung on the parent's thread pool")
    assert got == expected
    # A second fork generation (a worker's own child) works too.
    with multiprocessing.get_context("fork").Pool(1) as pool:
        assert pool.apply_async(_work, ((b, 4),)).get(timeout=120) == _work((b, 4))


def _corrupt(path):
    """Flips one bit in the middle of the file: inside the compressed chunks, which are most of
    a single-table file."""
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x10
    path.write_bytes(bytes(data))


def test_a_lazily_opened_corrupt_table_stays_failed(tmp_path):
    table = tmp_path / "c.btdb"
    brdftab.bake(GGX, str(table), preset="small")
    _corrupt(table)
    with pytest.raises(brdftab.Error, match="checksum"):
        brdftab.open(str(table))  # eager: the open checks every chunk
    lazy = brdftab.open(str(table), eager=False)
    with pytest.raises(brdftab.Error, match="checksum"):
        lazy.eval(upper(5000), upper(5000, 1))
    for _ in range(2):  # and stays failed, even for one pair
        with pytest.raises(brdftab.Error, match="checksum") as e:
            lazy.eval([0, 0, 1], [0, 0, 1])
    # The library's message names the file; the binding does not name it a second time.
    assert str(e.value).count(str(table)) == 1, str(e.value)
    with pytest.raises(brdftab.Error, match="checksum"):
        lazy.pdf([0, 0, 1], [0, 0, 1])


def test_check_and_albedo_of_a_corrupt_table_are_its_error(tmp_path):
    """`brdftab.check` opens lazily: on a table whose chunk fails its checksum it reported on
    the zeros read in the chunk's place (max albedo 0.928 for 0.995) and raised nothing."""
    table = tmp_path / "c.btdb"
    brdftab.bake(GGX, str(table), preset="small")
    _corrupt(table)
    with pytest.raises(brdftab.Error, match="checksum"):
        brdftab.check(str(table))
    with pytest.raises(brdftab.Error, match="checksum"):
        brdftab.open(str(table), eager=False).albedo([0.0, 0.5, 1.0])


def test_a_lazy_table_whose_file_is_cut_short_in_place_raises(tmp_path):
    """A table opened with eager=False read its chunks through a memory map: another program
    truncating the file in place (`cp other.btdb db.btdb`) killed Python with SIGBUS at the
    next lookup. Run in a child process, so a regression fails this test, not the run."""
    table = tmp_path / "q.btdb"
    brdftab.bake(GGX, str(table), preset="small")
    code = (
        "import brdftab, sys\n"
        f"b = brdftab.open({str(table)!r}, eager=False)\n"
        f"open({str(table)!r}, 'r+b').truncate(100)\n"
        "try:\n"
        "    b.eval([[0.3, 0.1, 0.9]], [[-0.3, 0.0, 0.95]])\n"
        "except brdftab.Error as e:\n"
        "    print(e); sys.exit(0)\n"
        "sys.exit(1)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, (r.returncode, r.stderr)
    assert "cut short" in r.stdout, r.stdout


def test_bake_and_save_refuse_a_measured_files_name(tmp_path):
    """`bake(SPEC, "m.bsdf")` wrote a brdftab table that then opened as an RGL file and was
    refused ("m.binary": as a truncated MERL file)."""
    for name in ["m.bsdf", "m.binary"]:
        with pytest.raises(ValueError, match="give it a .btdb name"):
            brdftab.bake(GGX, str(tmp_path / name), preset="small")
        assert not (tmp_path / name).exists()
        with pytest.raises(ValueError, match="give it a .btdb name"):
            brdftab.open(GGX).table(preset="small").save(str(tmp_path / name))
        assert not (tmp_path / name).exists()


def test_a_fifo_as_source_is_refused_at_once(tmp_path):
    fifo = tmp_path / "pipe.btdb"
    os.mkfifo(fifo)
    code = (
        "import brdftab, sys\n"
        "try:\n"
        f"    brdftab.open({str(fifo)!r})\n"
        "except brdftab.Error as e:\n"
        "    print(e); sys.exit(0)\n"
        "sys.exit(1)\n"
    )
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail("brdftab.open on a FIFO blocked")
    assert r.returncode == 0, r.stderr
    assert "not a regular file" in r.stdout
    with pytest.raises(brdftab.Error, match="a directory"):
        brdftab.open(str(tmp_path))


def ggx_as(source, tmp_path):
    """The GGX spec itself, or its small table."""
    if source == "spec":
        return brdftab.open(GGX)
    brdftab.bake(GGX, str(tmp_path / "t.btdb"), preset="small")
    return brdftab.open(str(tmp_path / "t.btdb"))


@pytest.mark.parametrize("source", ["spec", "table"])
def test_nan_directions_give_zero_as_in_every_host(tmp_path, source):
    b = ggx_as(source, tmp_path)
    good = [0.2, 0.1, 0.9]
    bad = [[np.nan, 0, 1], [0, np.inf, 1], [0, 0, 0], [0, 0, -np.inf]]
    for d in bad:
        assert b.eval(d, good).tolist() == [0, 0, 0]
        assert b.eval(good, d).tolist() == [0, 0, 0]
        assert b.pdf(d, good) == 0 and b.pdf(good, d) == 0
        wi, pdf, w = b.sample(d, [0.3, 0.6])
        assert wi.tolist() == [0, 0, 0] and pdf == 0 and w.tolist() == [0, 0, 0]
    # A batch mixing good and bad rows: only the bad rows are 0.
    wi = np.array([good, bad[0], good])
    f = b.eval(wi, [good] * 3)
    assert (f[1] == 0).all() and (f[0] > 0).all() and (f[0] == f[2]).all()
    with pytest.raises(ValueError, match=r"\[0, 1\)"):
        b.sample([0, 0, 1], [np.nan, 0.5])


@pytest.mark.parametrize("source", ["spec", "table"])
def test_directions_of_any_finite_length_are_directions(tmp_path, source):
    # Scaled by 1e308 or 1e-300 (squared lengths that overflow or underflow) a pair gives what
    # the unit pair gives; f and pdf were 0 while sample drew from the same wo.
    b = ggx_as(source, tmp_path)
    wi = np.array([-0.3, 0.1, 0.9]) / math.sqrt(0.91)
    wo = np.array([0.4, 0.2, 0.85]) / math.sqrt(0.9225)
    f, p = b.eval(wi, wo), b.pdf(wi, wo)
    s_wi, s_pdf, s_w = b.sample(wo, [0.3, 0.6])
    assert p > 0 and s_pdf > 0
    for k in [1e308, 1e-300]:
        np.testing.assert_allclose(b.eval(wi * k, wo * k), f, rtol=1e-6)
        np.testing.assert_allclose(b.pdf(wi * k, wo * k), p, rtol=1e-9)
        t_wi, t_pdf, t_w = b.sample(wo * k, [0.3, 0.6])
        np.testing.assert_allclose(t_wi, s_wi, atol=1e-12)
        np.testing.assert_allclose(t_pdf, s_pdf, rtol=1e-9)
        np.testing.assert_allclose(t_w, s_w, rtol=1e-6)


def test_an_error_about_a_huge_spec_is_short(tmp_path):
    big = "x" * (10 << 20)
    for spec in ('{"model": "%s"}' % big, '{"model": "lambert", "kd": "%s"}' % big):
        with pytest.raises(brdftab.Error) as e:
            brdftab.open(spec)
        assert len(str(e.value)) < 2000


# Counts no memory holds: each used to abort the interpreter (a failed allocation of
# `pairs` × channels samples) or raise "internal error (please report)" (an overflow). Run in a
# child so that a regression fails this test instead of killing pytest.
@pytest.mark.parametrize("call", [
    "brdftab.convert(LAMBERT, d + '/c.btdb', preset='small', pairs=2**62)",
    "brdftab.convert(LAMBERT, d + '/c.bsdf', pairs=2**62)",
    "brdftab.convert(LAMBERT, d + '/c.btdb', preset='small', pairs=2**64 - 1)",
    "brdftab.fit(LAMBERT, 'ggx', pairs=10**10, starts=1)",
    "brdftab.fit(LAMBERT, 'ggx', pairs=2**63 - 1, starts=1)",
])
def test_a_count_of_pairs_beyond_memory_is_a_value_error(tmp_path, call):
    code = (
        "import brdftab\n"
        f"d = {str(tmp_path)!r}\n"
        "LAMBERT = '{\"model\": \"lambert\", \"kd\": 0.5}'\n"
        "try:\n"
        f"    {call}\n"
        "except ValueError as e:\n"
        "    assert 'pairs' in str(e), e\n"
        "    print('refused')\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stdout.strip() == "refused", (r.returncode, r.stdout, r.stderr[-2000:])
