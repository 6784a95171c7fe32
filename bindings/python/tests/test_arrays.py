"""What numpy users pass to the array-taking calls (eval, eval_spectral, pdf, sample, albedo):
masked arrays, broadcast views of any length, wavelengths that are none. Each is read as
numpy reads it or refused with a ValueError/MemoryError naming the argument; none is silently
wrong and none aborts the interpreter."""

import subprocess
import sys
import tracemalloc

import numpy as np
import pytest

import brdftab

GGX = '{"model": "ggx", "alpha": 0.3, "fresnel": {"conductor": "Cu"}}'
WI = np.array([[0.3, 0.1, 0.9], [0.0, 0.0, 1.0], [-0.4, 0.2, 0.8]])
WO = np.array([[0.0, 0.0, 1.0], [0.2, 0.0, 0.9], [0.5, -0.5, 0.7]])
U = np.array([[0.1, 0.2], [0.5, 0.5], [0.9, 0.3]])
NM = np.array([450.0, 550.0, 650.0])
THETA = np.array([0.1, 0.7, 1.2])


def masked(a, row):
    """`a` as a masked array with one entry of `row` masked (its data left as it is)."""
    mask = np.zeros(a.shape, bool)
    mask[row if a.ndim == 1 else (row, 0)] = True
    return np.ma.masked_array(a, mask=mask)


# Every array argument of every call: (call, the position of the argument, its name).
CALLS = [
    ("eval", (WI, WO), 0, "wi"),
    ("eval", (WI, WO), 1, "wo"),
    ("eval_spectral", (WI, WO, NM), 0, "wi"),
    ("eval_spectral", (WI, WO, NM), 2, "nm"),
    ("pdf", (WI, WO), 1, "wo"),
    ("sample", (WO, U), 0, "wo"),
    ("sample", (WO, U), 1, "u"),
    ("albedo", (THETA,), 0, "theta"),
]


@pytest.mark.parametrize("call,args,k,name", CALLS)
def test_a_masked_array_with_masked_entries_is_refused(call, args, k, name):
    """Masked entries used to be evaluated as if valid (the mask was ignored)."""
    b = brdftab.open(GGX)
    args = list(args)
    args[k] = masked(args[k], 1)
    with pytest.raises(ValueError, match=f"{name}: a masked array with masked entries"):
        getattr(b, call)(*args)


@pytest.mark.parametrize("call,args,k,name", CALLS)
def test_a_masked_array_without_masked_entries_is_its_data(call, args, k, name):
    b = brdftab.open(GGX)
    ref = getattr(b, call)(*args)
    for m in (np.ma.masked_array(args[k]), np.ma.masked_array(args[k], mask=False)):
        got = getattr(b, call)(*[m if i == k else a for i, a in enumerate(args)])
        for x, y in zip(ref if isinstance(ref, tuple) else [ref],
                        got if isinstance(got, tuple) else [got]):
            assert type(y) is np.ndarray
            np.testing.assert_array_equal(x, y)


def test_a_wavelength_that_is_none_is_a_value_error():
    """nm <= 0 was evaluated (at the first channel); the library's rule for a wavelength is
    the one `wavelengths=` keeps: finite and > 0."""
    b = brdftab.open(GGX)
    for bad in ([0.0], [550.0, -5.0], [[500.0], [0.0], [600.0]], [np.nan], [np.inf]):
        with pytest.raises(ValueError, match="nm: .* is not a wavelength"):
            b.eval_spectral(WI, WO, bad)
    assert b.eval_spectral(WI, WO, [1e-3, 550.0, 1e6]).shape == (3, 3)


# Run in a child: a regression aborts it (a failed allocation in Rust) instead of pytest.
@pytest.mark.parametrize("call", [
    # theta and nm of 2^40 entries without memory (zero strides): were copied into a Vec and
    # aborted the interpreter ("memory allocation of 8796093022208 bytes failed").
    "b.albedo(np.broadcast_to(0.5, (2**40,)))",
    "b.eval_spectral(WI, WO, np.broadcast_to(550.0, (2**40,)))",
    # A result beyond memory (n 10^6 × k 10^7 float32): was "internal error in brdftab
    # (please report): Python API call failed" (a panic where numpy had refused).
    "b.eval_spectral(np.tile(WI, (333334, 1)), WO[0], np.broadcast_to(550.0, (10**7,)))",
])
def test_a_result_beyond_memory_is_a_memory_error(call):
    code = (
        "import numpy as np, brdftab\n"
        f"b = brdftab.open({GGX!r})\n"
        f"WI = np.array({WI.tolist()}); WO = np.array({WO.tolist()})\n"
        "try:\n"
        f"    {call}\n"
        "except MemoryError as e:\n"
        "    print('refused')\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stdout.strip() == "refused", (r.returncode, r.stdout,
                                                                 r.stderr[-2000:])


def test_broadcast_views_are_read_in_place():
    """A zero-stride nm or theta (numpy.broadcast_to) gives what its copy gives."""
    b = brdftab.open(GGX)
    nm = np.broadcast_to(550.0, (4,))
    np.testing.assert_array_equal(b.eval_spectral(WI, WO, nm),
                                  b.eval_spectral(WI, WO, np.full(4, 550.0)))
    per_row = np.broadcast_to(NM[:, None], (3, 2))
    np.testing.assert_array_equal(b.eval_spectral(WI, WO, per_row),
                                  b.eval_spectral(WI, WO, per_row.copy()))
    th = np.broadcast_to(0.7, (3,))
    np.testing.assert_array_equal(b.albedo(th), b.albedo(np.full(3, 0.7)))
    np.testing.assert_array_equal(b.albedo(THETA[::-1]), b.albedo(THETA.copy()[::-1].copy()))
    assert b.albedo(0.7).shape == (3,) and b.albedo([]).shape == (0, 3)


def misaligned(a):
    """A copy of `a` whose data starts one byte past an aligned address (numpy's `aligned` flag
    off), as `np.frombuffer` at an odd offset makes."""
    raw = np.zeros(a.nbytes + 1, np.uint8)
    b = np.frombuffer(raw.data, dtype=a.dtype, count=a.size, offset=1).reshape(a.shape)
    b[...] = a
    assert not b.flags.aligned
    return b


def test_misaligned_arrays_of_every_kind_read_as_their_aligned_copies(tmp_path):
    """float64 and float32 rows, wavelengths and a table's values in a misaligned buffer: each
    was borrowed as a `&[f64]`/`&[f32]` slice or an ndarray view of misaligned data, undefined
    behaviour in Rust (an extension built with debug assertions aborted the interpreter:
    "slice::from_raw_parts requires the pointer to be aligned"). Now numpy copies them aligned
    first, and each result equals the aligned input's."""
    b = brdftab.open(GGX)
    for dt in (np.float64, np.float32):
        wi, wo, u = WI.astype(dt), WO.astype(dt), U.astype(dt)
        np.testing.assert_array_equal(b.eval(misaligned(wi), misaligned(wo)), b.eval(wi, wo))
        for got, want in zip(b.sample(misaligned(wo), misaligned(u)), b.sample(wo, u)):
            np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(brdftab.rgb_basis(misaligned(NM)), brdftab.rgb_basis(NM))
    out = str(tmp_path / "t.btdb")
    brdftab.bake('{"model": "lambert", "kd": 0.5}', out, preset="small", codec="f32")
    t = brdftab.open(out).table()
    np.testing.assert_array_equal(t.with_values(misaligned(t.values)).values, t.values)


def test_a_misaligned_input_beyond_memory_is_a_memory_error():
    """A misaligned float64 view (of bytes at an odd offset) is copied into aligned rows; with
    no memory left for the copy the interpreter aborted ("memory allocation of 480000000 bytes
    failed"). Run in a child under an address-space limit that holds the input, not a copy."""
    code = (
        "import resource, numpy as np, brdftab\n"
        f"b = brdftab.open({GGX!r})\n"
        "n = 20_000_000\n"
        "raw = np.zeros(n * 24 + 1, np.uint8)\n"
        "wi = np.frombuffer(raw.data, np.float64, count=n * 3, offset=1).reshape(n, 3)\n"
        "assert wi.ctypes.data % 8 != 0\n"
        "b.eval(wi[:20000], wi[:20000])  # the library's threads exist before the limit\n"
        "vm = next(int(l.split()[1]) * 1024 for l in open('/proc/self/status')\n"
        "          if l.startswith('VmSize:'))\n"
        "hard = resource.getrlimit(resource.RLIMIT_AS)[1]\n"
        "resource.setrlimit(resource.RLIMIT_AS, (vm + (200 << 20), hard))\n"
        "try:\n"
        "    b.eval(wi, [0, 0, 1])\n"
        "except MemoryError as e:\n"
        "    assert 'wi' in str(e), e\n"
        "    print('refused')\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stdout.strip() == "refused", (r.returncode, r.stdout,
                                                                 r.stderr[-2000:])


def test_leading_shapes_broadcast_as_numpy_broadcasts():
    """Directions (..., 3) and u (..., 2) of any leading shapes that broadcast (an image of
    directions, a grid wi[:, None] against wo[None, :]) were refused ("expected shape (n, 3)
    or (3,)"); numpy users broadcast. Each result equals the flat call on the arguments that
    numpy.broadcast_arrays gives, value for value, in the broadcast shape."""
    rng = np.random.default_rng(7)
    b = brdftab.open(GGX)

    def dirs(*shape):
        v = rng.normal(size=shape + (3,))
        v[..., 2] = np.abs(v[..., 2])
        return v

    def flat(x, lead, w):
        return np.ascontiguousarray(np.broadcast_to(x, lead + (w,))).reshape(-1, w)

    cases = [
        (dirs(4, 5), dirs(4, 5)),          # an image of pairs
        (dirs(4, 1), dirs(1, 5)),          # a grid: both sides copied by broadcasting
        (dirs(6)[:, None], dirs(7)),       # (6, 1, 3) against (7, 3)
        (dirs(2, 3, 4), dirs(4)),          # one side repeated along the leading axes
        (dirs(1, 1), dirs(3, 2)),          # one row of shape (1, 1, 3)
        (dirs(0, 4), dirs(1, 4)),          # no pairs
        (dirs(2, 3).astype(np.float32), dirs(3)),  # float32 read in place
    ]
    for wi, wo in cases:
        lead = np.broadcast_shapes(wi.shape[:-1], wo.shape[:-1])
        fi, fo = flat(wi, lead, 3), flat(wo, lead, 3)
        f = b.eval(wi, wo)
        assert f.shape == lead + (3,) and f.dtype == np.float32
        np.testing.assert_array_equal(f.reshape(-1, 3), b.eval(fi, fo))
        p = b.pdf(wi, wo)
        assert p.shape == lead
        np.testing.assert_array_equal(p.reshape(-1), b.pdf(fi, fo))
        s = b.eval_spectral(wi, wo, NM)
        assert s.shape == lead + (3,)
        np.testing.assert_array_equal(s.reshape(-1, 3), b.eval_spectral(fi, fo, NM))
        # One set of wavelengths per pair, in the pairs' shape.
        nm = 400.0 + 300.0 * rng.random(lead + (2,))
        s = b.eval_spectral(wi, wo, nm)
        np.testing.assert_array_equal(s.reshape(-1, 2),
                                      b.eval_spectral(fi, fo, nm.reshape(-1, 2)))

    u = rng.random((4, 1, 2))
    wo = dirs(5)
    fo, fu = flat(wo, (4, 5), 3), flat(u, (4, 5), 2)
    for kw in ({}, {"delta": True}, {"nm": NM}):
        got, want = b.sample(wo, u, **kw), b.sample(fo, fu, **kw)
        assert got[0].shape == (4, 5, 3) and got[1].shape == (4, 5)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g.reshape(w.shape), w)
    assert b.sample(wo, u, nm=np.full((4, 5, 2), 550.0))[2].shape == (4, 5, 2)

    th = np.array([[0.1, 0.5], [0.9, 1.3]])
    a = b.albedo(th)
    assert a.shape == (2, 2, 3)
    np.testing.assert_array_equal(a.reshape(-1, 3), b.albedo(th.reshape(-1)))

    # Shapes that do not broadcast, and a last axis that is not a direction's, are refused.
    with pytest.raises(ValueError, match=r"wi and wo: shapes \(4, 3\) and \(5, 3\) do not "
                                         r"broadcast"):
        b.eval(dirs(4), dirs(5))
    with pytest.raises(ValueError, match=r"wi: expected shape \(\.\.\., 3\)"):
        b.eval(np.zeros((3, 4)), dirs(3))
    with pytest.raises(ValueError, match=r"nm: expected shape \(k,\) or \(4, 5, k\)"):
        b.eval_spectral(dirs(4, 5), dirs(5), np.full((5, 2), 550.0))
    # One pair takes one set (k,): the message said "(k,) or (, k)".
    for nm in (np.full((1, 2), 550.0), 550.0):
        for call in (lambda: b.eval_spectral([0, 0, 1], [0, 0, 1], nm),
                     lambda: b.sample([0, 0, 1], [0.5, 0.5], nm=nm)):
            with pytest.raises(ValueError, match=r"nm: expected shape \(k,\) \(the k wavelengths "
                                                 r"of the one pair\), got"):
                call()
    with pytest.raises(ValueError, match="u: expected shape"):
        b.sample(dirs(2), np.zeros(3))


def test_an_array_converted_for_a_call_is_copied_once():
    """A Fortran-order or strided array of another dtype is converted once into C-order
    float64. (A Fortran-order float32 `wi` was converted keeping its order, then copied again
    into C order: two n×3 float64 copies at once, a peak of 48 bytes a pair; now one copy and
    the float32 output, 36.)"""
    b = brdftab.open(GGX)
    n = 200_000
    wi = np.random.default_rng(8).normal(size=(n, 3))
    wi[:, 2] = np.abs(wi[:, 2])
    for a in (np.asfortranarray(wi.astype(np.float32)), np.asfortranarray(wi.astype(np.int64)),
              wi.astype(np.float16)[::-1]):
        tracemalloc.start()
        try:
            tracemalloc.reset_peak()
            f = b.eval(a, [0, 0, 1])
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert f.shape == (n, 3)
        # one float64 copy (24 bytes a pair) and the float32 output (12): 36; two copies: 48
        assert peak < 42 * n, f"{a.dtype}: {peak / n:.0f} bytes a pair"


class _ForeignTensor:
    """An array of another library (a CPU torch tensor): numpy reads it through `__array__`,
    and its `dtype` is that library's (`torch.float32`), not numpy's."""

    def __init__(self, a):
        self.a = np.asarray(a)
        self.dtype = f"torch.{self.a.dtype}"
        self.shape = self.a.shape

    def __array__(self, dtype=None, copy=None):
        return self.a if dtype is None else self.a.astype(dtype)


def test_an_array_of_another_library_is_read_as_numpy_reads_it():
    """Anything numpy reads as real numbers is an array argument: a tensor whose dtype is not
    numpy's was a TypeError ("expected real numbers, got an array of dtype torch.float32"); a
    complex one stays a TypeError, its imaginary part not dropped."""
    b = brdftab.open(GGX)
    want = b.eval(WI, WO)
    for dt in (np.float32, np.float64, np.int64):
        x = WI.astype(dt) if dt != np.int64 else np.array([[0, 0, 1]] * 3)
        got = b.eval(_ForeignTensor(x), WO)
        np.testing.assert_array_equal(got, b.eval(x, WO))
    np.testing.assert_array_equal(b.eval(_ForeignTensor(WI), _ForeignTensor(WO)), want)
    np.testing.assert_array_equal(b.albedo(_ForeignTensor(THETA)), b.albedo(THETA))
    with pytest.raises(TypeError, match=r"wi: expected real numbers, got an array of dtype "
                                        r"complex128"):
        b.eval(_ForeignTensor(WI.astype(complex)), WO)
