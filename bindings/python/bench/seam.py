"""An anisotropic `.bsdf` file at fixed incident azimuths, as brdftab's reader and Mitsuba 3's
`measured` read it, against its source (session 42, "The warp's seam in anisotropic files").

    python bindings/python/bench/seam.py BRDFTAB FILE.bsdf SOURCE STEP_DEG [--pairs 20000]

For φi = 0°, 90° and 180°, on the stored azimuth and a quarter and half of STEP_DEG past it
(the file's azimuth spacing: 22.5 for `PHI_I=17`), θi uniform in cos θi and ωo uniform over
the hemisphere: the relative RMSE of f_r cos θi cos θo within 80° (both directions) and in the
grazing band (either past 80°), for `brdftab eval FILE` and Mitsuba's `measured` (scalar_rgb)
against `brdftab eval SOURCE`.
"""

import math
import subprocess
import sys

import mitsuba as mi
import numpy as np


def evaluate(brdftab, source, wi, wo):
    lines = "\n".join(" ".join(f"{x:.17g}" for x in (*a, *b)) for a, b in zip(wi, wo))
    out = subprocess.run(
        [brdftab, "eval", source], input=lines + "\n", capture_output=True, text=True, check=True
    ).stdout
    return np.array([[float(x) for x in l.split()] for l in out.strip().splitlines()])


def main():
    args = sys.argv[1:]
    pairs = 20000
    if "--pairs" in args:
        k = args.index("--pairs")
        pairs = int(args[k + 1])
        del args[k : k + 2]
    brdftab, path, source, step = args[0], args[1], args[2], float(args[3])
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict({"type": "measured", "filename": path})
    ctx, si = mi.BSDFContext(), mi.SurfaceInteraction3f()
    rng = np.random.default_rng(7)
    cap = math.cos(math.radians(80.0))
    print("| φi | brdftab: within 80° / grazing | Mitsuba 3: within 80° / grazing |")
    print("|---|---|---|")
    for centre in (0.0, 90.0, 180.0):
        for off in (0.0, 0.25, 0.5):
            phi = math.radians(centre + off * step)
            zi = rng.random(pairs)
            si_ = np.sqrt(1.0 - zi * zi)
            wi = np.stack([si_ * math.cos(phi), si_ * math.sin(phi), zi], 1)
            zo, po = rng.random(pairs), 2.0 * math.pi * rng.random(pairs)
            so = np.sqrt(1.0 - zo * zo)
            wo = np.stack([so * np.cos(po), so * np.sin(po), zo], 1)
            w = (wi[:, 2] * wo[:, 2])[:, None]
            ref = evaluate(brdftab, source, wi, wo) * w
            ours = evaluate(brdftab, path, wi, wo) * w
            theirs = np.zeros((pairs, 3))
            for k in range(pairs):
                si.wi = mi.Vector3f(*wi[k])
                v = bsdf.eval(ctx, si, mi.Vector3f(*wo[k]))  # f_r cos θo
                theirs[k] = [v[0] * wi[k, 2], v[1] * wi[k, 2], v[2] * wi[k, 2]]
            band = (wi[:, 2] < cap) | (wo[:, 2] < cap)

            def err(got, sel):
                return 100.0 * math.sqrt(np.sum((got[sel] - ref[sel]) ** 2) / np.sum(ref[sel] ** 2))

            print(
                f"| {centre:g}° + {off:g} step | {err(ours, ~band):.2f} / {err(ours, band):.2f} % "
                f"| {err(theirs, ~band):.2f} / {err(theirs, band):.2f} % |",
                flush=True,
            )


if __name__ == "__main__":
    main()
