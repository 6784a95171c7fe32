"""Sampling efficiency of the Mitsuba plugin against Mitsuba's own plugins (issue 24).

    python bindings/python/bench/efficiency.py [--files data/rgl/*.bsdf] [--spp 16] [--size 96]

A sphere under a constant environment and nothing else, llvm_ad_rgb, path tracer of depth 2:
BSDF sampling carries the image. For each material, each plugin renders its own converged
reference (64× the test's samples) and ``--rounds`` noisy images of ``--spp`` samples with other
seeds; MSE is against the plugin's own reference (so the table's small difference from the
file does not count), time is the median render time. Efficiency =
(MSE × time of Mitsuba's plugin) / (MSE × time of brdftab's): above 1, brdftab's plugin
reaches a given noise level sooner. RGL files compare with ``measured`` on the same file (the
plugin on its default table of the file, from the bake cache); the analytic case GGX copper
α = 0.1 with ``roughconductor``.
"""

import argparse
import json
import pathlib
import statistics
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[3]


def scene(mi, bsdf, size, spp):
    T = mi.ScalarTransform4f
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 24,
                   "to_world": T().look_at([0, -5, 2.5], [0, 0, 0], [0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": size, "height": size,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    })


def measure(mi, dr, bsdf, size, spp, rounds):
    ref = np.array(mi.render(scene(mi, bsdf, size, spp * 64), seed=12345))
    s = scene(mi, bsdf, size, spp)
    dr.eval(mi.render(s, seed=0))  # compile
    mse, times = [], []
    for k in range(rounds):
        t0 = time.perf_counter()
        img = mi.render(s, seed=k + 1)
        dr.eval(img)
        dr.sync_thread()
        times.append(time.perf_counter() - t0)
        mse.append(float(np.mean((np.array(img) - ref) ** 2)))
    return statistics.mean(mse), statistics.median(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--files", nargs="*",
                    default=sorted(str(p) for p in (ROOT / "data" / "rgl").glob("*.bsdf")))
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--size", type=int, default=96)
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--no-ggx", action="store_true")
    a = ap.parse_args()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import brdftab.mitsuba

    brdftab.mitsuba.register()
    cases = [(pathlib.Path(f).stem, {"type": "brdftab", "source": f},
              {"type": "measured", "filename": f}) for f in a.files]
    if not a.no_ggx:
        spec = '{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}'
        cases.append(("ggx_cu_0.1", {"type": "brdftab", "source": spec},
                      {"type": "roughconductor", "distribution": "ggx", "alpha": 0.1,
                       "material": "Cu"}))
    rows = []
    for name, ours, theirs in cases:
        m_o, t_o = measure(mi, dr, ours, a.size, a.spp, a.rounds)
        m_t, t_t = measure(mi, dr, theirs, a.size, a.spp, a.rounds)
        row = {"case": name, "mse_brdftab": m_o, "mse_mitsuba": m_t, "time_brdftab": t_o,
               "time_mitsuba": t_t, "efficiency": (m_t * t_t) / (m_o * t_o)}
        rows.append(row)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
