"""Benchmarks of the Python package and the Mitsuba plugin (issue 14's bars).

    python bindings/python/bench/bench.py [--rgl DIR] [--cli target/release/brdftab] [--png OUT]

1. Python batch eval of 10^6 pairs vs `brdftab bench`'s batch rate on the same table (a
   medium table baked from an RGL file), and the time of a one-pair call.
2. llvm_ad_rgb: render time of a 256x256, 64 spp scene with the plugin (that table) vs
   Mitsuba's `measured` on the RGL file (best of 4 interleaved renders after a warm-up render that compiles the kernels).
Figures are ratios within one run (the machine is shared; absolute times vary).
"""

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import brdftab

ROOT = pathlib.Path(__file__).resolve().parents[3]


def best(f, reps):
    t = []
    for _ in range(reps):
        t0 = time.perf_counter()
        f()
        t.append(time.perf_counter() - t0)
    return min(t)


def dirs(n, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=1)[:, None]


def python_vs_cli(table, cli):
    b = brdftab.open(table)
    wi, wo = dirs(1_000_000, 1), dirs(1_000_000, 2)
    b.eval(wi, wo)
    t = best(lambda: b.eval(wi, wo), 5)
    py_rate = 1e6 / t
    out = json.loads(subprocess.run([cli, "bench", table, "--json"], capture_output=True,
                                    text=True, check=True).stdout)
    one = best(lambda: [b.eval(wi[0], wo[0]) for _ in range(10000)], 3) / 10000
    return py_rate, out, one


def scene(mi, bsdf, spp=64, size=256):
    T = mi.ScalarTransform4f
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 4},
        "sensor": {"type": "perspective", "fov": 28,
                   "to_world": T().look_at([0, -5, 3], [0, 0, 0.1], [0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": size, "height": size},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "floor": {"type": "rectangle", "to_world": T().translate([0, 0, -1]).scale(4),
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.5}}},
        "light": {"type": "sphere", "center": [3, -2, 5], "radius": 0.7,
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 40}}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.15}},
    })


def render_times(rgl_file, table, png, rounds=4):
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import brdftab.mitsuba

    brdftab.mitsuba.register()
    scenes = {"plugin": scene(mi, {"type": "brdftab", "source": table}),
              "measured": scene(mi, {"type": "measured", "filename": rgl_file})}
    imgs = {}
    for name, s in scenes.items():  # warm-up: compiles the kernels
        dr.eval(mi.render(s, seed=0))
    times = {name: [] for name in scenes}
    for k in range(rounds):  # interleaved, so that load from other processes hits both alike
        for name, s in scenes.items():
            t0 = time.perf_counter()
            img = mi.render(s, seed=k + 1)
            dr.eval(img)
            dr.sync_thread()
            times[name].append(time.perf_counter() - t0)
            imgs[name] = np.array(img)
    res = {name: min(t) for name, t in times.items()}
    if png:
        both = np.concatenate([imgs["plugin"], imgs["measured"]], axis=1)
        mi.util.write_bitmap(png, mi.TensorXf(both))
    diff = abs(imgs["plugin"].mean() - imgs["measured"].mean()) / imgs["measured"].mean()
    return res, diff


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rgl", default=None)
    ap.add_argument("--cli", default=str(ROOT / "target" / "release" / "brdftab"))
    ap.add_argument("--png", default=None)
    ap.add_argument("--file", default="vch_golden_yellow_rgb.bsdf")
    a = ap.parse_args()
    rgl = pathlib.Path(a.rgl) if a.rgl else next(
        p for p in [ROOT / "data" / "rgl", ROOT.parent / "shared" / "data" / "measured" / "rgl"]
        if p.is_dir())
    rgl_file = str(rgl / a.file)
    with tempfile.TemporaryDirectory(prefix="brdftab-bench-") as d:
        table = os.path.join(d, "rgl.btdb")
        brdftab.bake(rgl_file, table, preset="medium")
        py_rate, cli_out, one = python_vs_cli(table, a.cli)
        print(f"brdftab bench: {json.dumps(cli_out)}")
        print(f"python batch eval 1e6 pairs: {py_rate / 1e6:.2f} M pairs/s")
        print(f"one-pair eval call: {one * 1e6:.2f} us")
        sys.stdout.flush()
        res, diff = render_times(rgl_file, table, a.png)
    print(f"llvm_ad_rgb 256x256 64spp: plugin {res['plugin']:.2f} s, measured {res['measured']:.2f} s "
          f"(ratio {res['plugin'] / res['measured']:.2f}); mean image difference {diff:.2%}")


if __name__ == "__main__":
    main()
