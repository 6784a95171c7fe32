"""Python batch calls against the library on the same arrays (issue 26, item 1).

    python bindings/python/bench/batch.py [--lib target/release/libbrdftab_c.so] [--n 1000000]

The library's rate is measured through the C ABI (``brdftab_eval``/``_pdf``/``_sample``, which
run ``Brdf::eval_batch``/``pdf_batch``/``sample_batch`` on the caller's arrays in place), loaded
with ctypes into this same process, on the same numpy arrays and the same table, interleaved
with the Python calls (median of the rounds; the machine is shared, so only ratios within one
run mean anything). Then the one-pair call's overhead, and the peak memory of a large eval in a
fresh process (growth of the peak RSS beyond the inputs, against the output's bytes).
"""

import argparse
import ctypes
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import brdftab

ROOT = pathlib.Path(__file__).resolve().parents[3]


def dirs(n, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=1)[:, None]


def c_library(path):
    lib = ctypes.CDLL(path)
    P, S = ctypes.c_void_p, ctypes.c_size_t
    lib.brdftab_open.restype = P
    lib.brdftab_open.argtypes = [ctypes.c_char_p]
    lib.brdftab_last_error.restype = ctypes.c_char_p
    lib.brdftab_channels.argtypes = [P]
    lib.brdftab_channels.restype = S
    for name, args in [("brdftab_eval", [P, S, P, P, P]), ("brdftab_pdf", [P, S, P, P, P]),
                       ("brdftab_sample", [P, S, P, P, P, P, P])]:
        f = getattr(lib, name)
        f.argtypes, f.restype = args, ctypes.c_int
    return lib


def ptr(a):
    return a.ctypes.data_as(ctypes.c_void_p)


def median_time(f, reps):
    t = []
    for _ in range(reps):
        t0 = time.perf_counter()
        f()
        t.append(time.perf_counter() - t0)
    return statistics.median(t)


def rates(source, lib_path, n, rounds):
    b = brdftab.open(source)
    lib = c_library(lib_path)
    h = lib.brdftab_open(source.encode())
    if not h:
        raise SystemExit(f"C open failed: {lib.brdftab_last_error().decode()}")
    c = lib.brdftab_channels(h)
    wi, wo = dirs(n, 1), dirs(n, 2)
    u = np.random.default_rng(3).random((n, 2))
    f = np.zeros((n, c), np.float32)
    p = np.zeros(n)
    s_wi, s_w = np.zeros((n, 3)), np.zeros((n, c), np.float32)

    def c_eval():
        assert lib.brdftab_eval(h, n, ptr(wi), ptr(wo), ptr(f)) == 0

    def c_pdf():
        assert lib.brdftab_pdf(h, n, ptr(wi), ptr(wo), ptr(p)) == 0

    def c_sample():
        assert lib.brdftab_sample(h, n, ptr(wo), ptr(u), ptr(s_wi), ptr(p), ptr(s_w)) == 0

    calls = {
        "eval": (lambda: b.eval(wi, wo), c_eval),
        "pdf": (lambda: b.pdf(wi, wo), c_pdf),
        "sample": (lambda: b.sample(wo, u), c_sample),
    }
    # Same results first: the comparison is of the same work.
    c_eval()
    np.testing.assert_array_equal(b.eval(wi, wo), f)
    out = {}
    for name, (py, cc) in calls.items():
        py(), cc()  # warm: sampling structures built, pages touched
        tp, tc = [], []
        for _ in range(rounds):  # interleaved
            tp.append(median_time(py, 1))
            tc.append(median_time(cc, 1))
        out[name] = {"python_Mpairs_s": n / statistics.median(tp) / 1e6,
                     "library_Mpairs_s": n / statistics.median(tc) / 1e6,
                     "ratio": statistics.median(tc) / statistics.median(tp)}
    # One-pair calls: the Python call, a getter of the same object (`channels`: the floor of a
    # call into the extension), and the library's cost of one pair (the C batch rate).
    one_wi, one_wo = wi[0].copy(), wo[0].copy()
    k = 20000
    t_one = median_time(lambda: [b.eval(one_wi, one_wo) for _ in range(k)], 5) / k
    t_attr = median_time(lambda: [b.channels for _ in range(k)], 5) / k
    out["one_pair"] = {"eval_us": t_one * 1e6, "getter_us": t_attr * 1e6,
                       "library_pair_us": 1 / (out["eval"]["library_Mpairs_s"] * 1e6) * 1e6}
    lib.brdftab_close.argtypes = [ctypes.c_void_p]
    lib.brdftab_close(h)
    return out


MEMORY = r"""
import resource, sys, numpy as np, brdftab
n = int(sys.argv[2])
b = brdftab.open(sys.argv[1], eager=True)  # decoded whole: the eval's own memory only
rng = np.random.default_rng(1)
wi = rng.normal(size=(n, 3)); wi[:, 2] = abs(wi[:, 2])
wo = rng.normal(size=(n, 3)); wo[:, 2] = abs(wo[:, 2])
b.eval(wi[:10], wo[:10])
rss = lambda: int(open("/proc/self/statm").read().split()[1]) * resource.getpagesize()
before = rss()
f = b.eval(wi, wo)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(before, peak, f.nbytes, wi.nbytes + wo.nbytes)
"""


def memory(source, n):
    r = subprocess.run([sys.executable, "-c", MEMORY, source, str(n)], capture_output=True,
                       text=True, check=True)
    before, peak, out_bytes, in_bytes = map(int, r.stdout.split())
    return {"pairs": n, "inputs_MB": in_bytes / 1e6, "output_MB": out_bytes / 1e6,
            "peak_growth_MB": (peak - before) / 1e6}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lib", default=str(ROOT / "target" / "release" / "libbrdftab_c.so"))
    ap.add_argument("--file", default=str(ROOT / "data" / "rgl" / "vch_golden_yellow_rgb.bsdf"))
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--memory-pairs", type=int, default=20_000_000)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        table = os.path.join(d, "t.btdb")
        brdftab.bake(a.file, table)  # the default bake of the RGL file
        res = {"table": f"default bake of {os.path.basename(a.file)}", "threads": os.cpu_count()}
        res.update(rates(table, a.lib, a.n, a.rounds))
        res["memory"] = memory(table, a.memory_pairs)
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
