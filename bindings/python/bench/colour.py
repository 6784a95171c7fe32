"""Colour through a spectral renderer: each RGB file as the spectrum brdftab gives it at
wavelengths, projected as a renderer's film projects it, against the file's own RGB.

    python bindings/python/bench/colour.py [--files data/rgl/*.bsdf] [--step 10] [--pairs 2000]

For every file: ``eval_spectral`` at 360-830 nm every ``--step`` nm (what ``brdftab convert
--wavelengths`` writes for pbrt-v4), interpolated linearly between samples as pbrt reads them,
projected to linear sRGB by Mitsuba 3's ``spectrum_list_to_srgb(..., d65=True)`` (an
implementation of the CIE 1931 / D65 projection independent of brdftab's, divided by its
projection of 1) — against the file's RGB; the mean of f_r cos θi cos θo over random pairs within
80°, per channel, relative to the largest channel. ``old`` is the representative-wavelength rule
brdftab used before session 33 (B, G, R at 444, 526, 645 nm, linear between), for comparison.
"""

import argparse
import glob
import math
import os
import pathlib

import numpy as np

import brdftab

ROOT = pathlib.Path(__file__).resolve().parents[3]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--files", nargs="*", default=sorted(glob.glob(str(ROOT / "data/rgl/*.bsdf"))))
    ap.add_argument("--step", type=float, default=10.0)
    ap.add_argument("--pairs", type=int, default=2000)
    a = ap.parse_args()

    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    wl1 = np.arange(360.0, 831.0)
    wl = np.arange(360.0, 830.0 + 1e-9, a.step)

    def project(v):
        return np.array(mi.spectrum_list_to_srgb(list(wl1), [float(x) for x in v], False, True))

    white = project(np.ones_like(wl1))
    rng = np.random.default_rng(7)

    def dirs(n):
        c = rng.uniform(math.cos(math.radians(80)), 1, n)
        p = rng.uniform(0, 2 * math.pi, n)
        s = np.sqrt(1 - c * c)
        return np.stack([s * np.cos(p), s * np.sin(p), c], 1)

    wi, wo = dirs(a.pairs), dirs(a.pairs)
    w = (wi[:, 2] * wo[:, 2])[:, None]
    print(f"{'file':22s} {'old: R G B':>24s} {'now: R G B':>24s}")
    for f in a.files:
        b = brdftab.open(f)
        rgb = (b.eval(wi, wo).astype(float) * w).sum(0)
        spectrum = (b.eval_spectral(wi, wo, wl).astype(float) * w).sum(0)
        now = project(np.interp(wl1, wl, spectrum)) / white
        old = project(np.interp(wl1, [444.0, 526.0, 645.0], rgb[::-1])) / white
        fmt = lambda v: " ".join(f"{x:+6.1%}" for x in (v - rgb) / rgb.max())
        name = os.path.basename(f).removesuffix(".bsdf").removesuffix("_rgb")
        print(f"{name:22s} {fmt(old):>24s} {fmt(now):>24s}")


if __name__ == "__main__":
    main()
