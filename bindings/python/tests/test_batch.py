"""Batch calls at the library's cost (issue 26, item 1): arrays read in place, results written
into the returned arrays, the GIL released, every input layout giving the same numbers."""

import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import brdftab

GGX = '{"model": "ggx", "alpha": 0.3, "fresnel": {"conductor": "Cu"}}'
# Larger than the library's parallel threshold (4 blocks of 4096 pairs), not a multiple of it.
N = 4 * 4096 + 4096 // 2 + 7


def upper(n, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.05
    return v / np.linalg.norm(v, axis=1)[:, None]


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    p = tmp_path_factory.mktemp("batch") / "ggx.btdb"
    brdftab.bake(GGX, str(p), preset="small")
    return brdftab.open(str(p))


@pytest.mark.parametrize("layout", ["fortran", "strided", "reversed", "rows", "packed",
                                    "float32", "misaligned", "list"])
def test_every_layout_gives_the_contiguous_result(table, layout):
    """Read in place (C order, Fortran order, columns of a wider array, reversed, every other
    row, float32), or copied once (strides of no whole float64, a misaligned buffer, a list):
    the numbers of the C-ordered float64 array, for eval, pdf and sample alike."""
    wi, wo = upper(N, 1), upper(N, 2)
    ref = table.eval(wi, wo)

    def convert(a):
        if layout == "fortran":
            return np.asfortranarray(a)
        if layout == "strided":
            w = a.shape[1]
            b = np.zeros((a.shape[0], w + 2))
            b[:, 1:w + 1] = a
            return b[:, 1:w + 1]
        if layout == "reversed":
            return np.ascontiguousarray(a[::-1])[::-1]
        if layout == "rows":
            b = np.zeros((2 * a.shape[0], a.shape[1]))
            b[1::2] = a
            return b[1::2]
        if layout == "packed":
            b = np.zeros(a.shape[0], dtype=[("tag", "u1"), ("v", "f8", a.shape[1])])
            b["v"] = a
            assert b["v"].strides[0] % 8 != 0
            return b["v"]
        if layout == "float32":
            return a.astype(np.float32)
        if layout == "misaligned":
            raw = np.zeros(a.nbytes + 1, np.uint8)
            b = np.frombuffer(raw.data, dtype=np.float64, count=a.size, offset=1).reshape(a.shape)
            b[...] = a
            assert b.ctypes.data % 8 != 0
            return b
        return a.tolist()

    got = table.eval(convert(wi), convert(wo))
    if layout == "float32":
        np.testing.assert_array_equal(got, table.eval(wi.astype(np.float32).astype(np.float64),
                                                      wo.astype(np.float32).astype(np.float64)))
    else:
        np.testing.assert_array_equal(got, ref)
    np.testing.assert_array_equal(table.pdf(convert(wi), convert(wo)), table.pdf(
        np.asarray(convert(wi), np.float64), np.asarray(convert(wo), np.float64)))
    u = np.random.default_rng(3).random((N, 2))
    for got, want in zip(table.sample(convert(wo), convert(u)),
                         table.sample(np.asarray(convert(wo), np.float64),
                                      np.asarray(convert(u), np.float64))):
        np.testing.assert_array_equal(got, want)


def test_float32_arrays_read_in_place_give_their_float64_values(table):
    """C-contiguous float32 rows are widened block by block in the binding, not copied by numpy
    before the call: every call gives exactly what the same numbers in float64 give — whole
    arrays past the parallel threshold, one float32 row against float64 rows, float32 u, a
    float32 view that is not contiguous (numpy's copy), a masked float32 array without masked
    entries, no rows."""
    wi, wo = upper(N, 6).astype(np.float32), upper(N, 7).astype(np.float32)
    u = np.random.default_rng(8).random((N, 2)).astype(np.float32)
    w64 = lambda a: np.asarray(a, np.float64)  # noqa: E731
    nm = np.array([450.0, 550.0, 650.0])
    cases = [
        (lambda a, b: table.eval(a, b), (wi, wo)),
        (lambda a, b: table.pdf(a, b), (wi, wo)),
        (lambda a, b: table.eval(a, b), (wi, w64(wo[5]))),
        (lambda a, b: table.eval(a, b), (wi[3], w64(wo))),
        (lambda a, b: table.eval_spectral(a, b, nm), (wi, wo)),
        (lambda a, b: table.sample(a, b), (wo, u)),
        (lambda a, b: table.sample(a, b), (wo[9], u)),
        (lambda a, b: table.sample(a, b, nm=nm), (wo, u)),
        (lambda a, b: table.sample(a, b, delta=True), (wo, u)),
        (lambda a, b: table.eval(a, b), (wi[::2], wo[::2])),
        (lambda a, b: table.eval(a, b), (np.ma.MaskedArray(wi), wo)),
        (lambda a, b: table.eval(a, b), (wi[:0], wo[:0])),
    ]
    for k, (f, (a, b)) in enumerate(cases):
        got, ref = f(a, b), f(w64(a), w64(b))
        for g, r in zip(*[(x,) if isinstance(x, np.ndarray) else x for x in (got, ref)]):
            assert g.dtype == r.dtype and g.shape == r.shape, k
            np.testing.assert_array_equal(g, r, err_msg=f"case {k}")


def test_a_single_row_broadcasts_like_its_repeat(table):
    """One row against many, past the block size and the parallel threshold: the same numbers
    as the row repeated (the binding repeats it per block, never n times)."""
    wi, wo = upper(N, 3), upper(N, 4)
    one = wo[17]
    rep = np.repeat(one[None, :], N, axis=0)
    np.testing.assert_array_equal(table.eval(wi, one), table.eval(wi, rep))
    # One row of shape (1, 3) broadcasts as (3,) does (numpy's rule; it used to be refused
    # with a message that offered "or one row").
    np.testing.assert_array_equal(table.eval(wi, one[None, :]), table.eval(wi, rep))
    np.testing.assert_array_equal(table.eval(one[None, :], wi), table.eval(rep, wi))
    assert table.eval(one[None, :], one).shape == (1, 3)
    np.testing.assert_array_equal(table.eval(one, wi), table.eval(rep, wi))
    np.testing.assert_array_equal(table.pdf(wi, one), table.pdf(wi, rep))
    u = np.random.default_rng(5).random((N, 2))
    for a, b in zip(table.sample(one, u), table.sample(rep, u)):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(table.sample(wo, u[3]), table.sample(wo, np.repeat(u[3:4], N, axis=0))):
        np.testing.assert_array_equal(a, b)
    nm = np.array([450.0, 550.0, 650.0])
    np.testing.assert_array_equal(table.eval_spectral(wi, one, nm),
                                  table.eval_spectral(wi, rep, nm))


def test_batches_equal_one_pair_calls(table):
    wi, wo = upper(N, 6), upper(N, 7)
    u = np.random.default_rng(8).random((N, 2))
    f, p = table.eval(wi, wo), table.pdf(wi, wo)
    s_wi, s_pdf, s_w = table.sample(wo, u)
    for k in [0, 4095, 4096, N - 1]:
        np.testing.assert_array_equal(f[k], table.eval(wi[k], wo[k]))
        assert p[k] == table.pdf(wi[k], wo[k])
        one = table.sample(wo[k], u[k])
        np.testing.assert_array_equal(s_wi[k], one[0])
        assert s_pdf[k] == one[1]
        np.testing.assert_array_equal(s_w[k], one[2])


def test_results_are_fresh_writable_arrays(table):
    wi = upper(8, 9)
    f = table.eval(wi, wi)
    assert f.flags.c_contiguous and f.flags.writeable and f.flags.owndata
    f[:] = 0  # the caller's to keep or change
    assert table.eval(wi, wi).any()


def test_the_gil_is_released_during_a_batch(table):
    """A Python thread keeps running while a long eval runs (it could not if the call held
    the GIL)."""
    wi, wo = upper(2_000_000, 10), upper(2_000_000, 11)
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())

    t = threading.Thread(target=count)
    t.start()
    time.sleep(0.01)
    t0 = time.perf_counter()
    table.eval(wi, wo)
    t1 = time.perf_counter()
    stop.set()
    t.join()
    inside = [x for x in ticks if t0 < x < t1]
    # The counting thread ran during the call: many ticks spread over it, not one burst at
    # a GIL switch interval (5 ms) boundary.
    assert t1 - t0 > 0.02, "the call was too short to tell"
    assert len(inside) > 1000, (len(inside), t1 - t0)
    assert inside[-1] - inside[0] > 0.5 * (t1 - t0)


MEMORY = r"""
import sys, numpy as np, brdftab
b = brdftab.open(sys.argv[1], eager=True)
n = 4_000_000
rng = np.random.default_rng(1)
wi = rng.normal(size=(n, 3)); wi[:, 2] = abs(wi[:, 2])
wo = rng.normal(size=(n, 3)); wo[:, 2] = abs(wo[:, 2])
layout = {"fortran": np.asfortranarray, "reversed": lambda a: np.ascontiguousarray(a[::-1])[::-1]}
if sys.argv[2] in layout:
    wi, wo = layout[sys.argv[2]](wi), layout[sys.argv[2]](wo)
else:
    wi, wo = wi.astype(sys.argv[2]), wo.astype(sys.argv[2])
b.eval(wi[:10], wo[:10])
def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key + ":"):
            return int(line.split()[1]) * 1024
# The peak is this process's own (VmHWM), reset to the current RSS here. Not getrusage's
# ru_maxrss: a child started by vfork + exec (Python's subprocess) inherits its parent's peak
# there, so after a test that had grown the pytest process it measured the parent.
open("/proc/self/clear_refs", "w").write("5")
rss, file0 = status("VmRSS"), status("RssFile")
f = b.eval(wi, wo)
peak = status("VmHWM")
# Pages of mapped files (the extension's code) faulted in again during the call count in the
# RSS but are not the call's memory.
print(peak - rss - max(status("RssFile") - file0, 0), f.nbytes)
"""


@pytest.mark.parametrize("dtype", ["float64", "float32", "fortran", "reversed"])
def test_a_large_eval_needs_about_its_output(tmp_path, dtype):
    """4e6 pairs (inputs 192 MB, result 48 MB): the process grows by the result, not by
    copies of the inputs (432 MB before the inputs were read in place; float32 inputs, 96 MB,
    grew it by their float64 copies, 192 MB, before they were read in place; Fortran-ordered
    and reversed float64 inputs by their C-ordered copies, 192 MB, too). Measured in a fresh
    process, whatever ran before in this one: the peak below stands for earlier tests (the
    Mitsuba plugin's, a large batch) that left this process with a high-water mark above the
    child's."""
    p = tmp_path / "ggx.btdb"
    brdftab.bake(GGX, str(p), preset="small")
    peak = np.ones(600_000_000 // 8)  # 600 MB touched: this process's peak, above the child's
    del peak
    r = subprocess.run([sys.executable, "-c", MEMORY, str(p), dtype], capture_output=True,
                       text=True, check=True)
    growth, out = map(int, r.stdout.split())
    # The result (locally to 0.1 MB), plus slack: one CI run on a busy machine saw 49 MB more
    # in the whole RSS, not reproduced — file-backed pages of the 40 MB extension evicted and
    # faulted in again are the suspect, now subtracted; the slack stays in case it was
    # something else. A float64 copy of one input alone is 96 MB (the old binding grew by
    # 432 MB; on float32 inputs by 240 MB).
    assert growth < out + 64e6, (growth, out)
