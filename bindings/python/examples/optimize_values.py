"""Fit a brdftab table to images in Mitsuba 3: the plugin's table values are a differentiable
scene parameter, so an inverse-rendering loop can optimize them like any texture.

The target here is a render of Mitsuba's own ``roughconductor`` (GGX copper, α = 0.3) — any
images of a material would do — and the start a Lambert table on the small preset's grid. Adam
moves the table's values until renders of it match the target from a few views, then the fitted
table is exported and saved as a brdftab table (``brdftab.open`` reads it; the plugin, the CLI
and the C ABI render it).

    python optimize_values.py fitted.btdb [--iterations 40] [--size 48] [--spp 8]

Needs an AD variant (``llvm_ad_rgb``: ``apt-get install libllvm19`` and
``DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1``, or ``cuda_ad_rgb``).
"""

from __future__ import annotations

import argparse
import os
import tempfile

import drjit as dr
import mitsuba as mi
import numpy as np

import brdftab

#: The material the target images show (Mitsuba's closed form, not a table).
TARGET = {"type": "roughconductor", "material": "Cu", "alpha": 0.3, "distribution": "ggx"}
#: Where the fit starts: a grey Lambert, baked on the grid the fitted table will have.
START = '{"model": "lambert", "kd": 0.1}'
#: Camera positions: the sphere seen from the light's side and from grazing views.
VIEWS = ([0, -4, 1.5], [3, -2.5, 0.5], [-3, -2, 2.5])


def scene(bsdf: dict, origin, size: int, spp: int):
    """A unit sphere under a point light and a dim constant environment, seen from ``origin``;
    direct illumination only (``prb``, two vertices)."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "prb", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(
                       origin=origin, target=[0, 0, 0], up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": size, "height": size,
                            "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "light": {"type": "point", "position": [2, -2, 3],
                  "intensity": {"type": "rgb", "value": 20}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.2}},
    })


def renders(bsdf: dict, size: int, spp: int, seed: int = 0):
    """Renders of ``bsdf`` from every view."""
    return [mi.render(scene(bsdf, o, size, spp), spp=spp, seed=seed + k)
            for k, o in enumerate(VIEWS)]


def image_loss(images, targets) -> float:
    """Mean squared error over the views."""
    loss = sum(dr.mean(dr.square(a - b), axis=None) for a, b in zip(images, targets))
    return float(np.array(loss).ravel()[0]) / len(targets)


def optimize(output: str, iterations: int = 40, size: int = 48, spp: int = 8,
             lr: float = 0.02, log=print) -> dict:
    """Fits the table and saves it to ``output`` (a ``.btdb`` file or ``DB#NAME``). Returns
    {"losses": the image loss at every iteration, "start": the start table's loss and
    "saved": the saved table's, each rendered again with fresh samples}."""
    if not mi.variant() or "_ad_" not in mi.variant():
        mi.set_variant("llvm_ad_rgb")
    import brdftab.mitsuba

    brdftab.mitsuba.register()
    targets = renders(TARGET, size, 8 * spp, seed=1000)
    with tempfile.TemporaryDirectory() as tmp:
        start = os.path.join(tmp, "start.btdb")
        brdftab.bake(START, start, preset="small", calibrate=False)
        scenes = [scene({"type": "brdftab", "source": start}, o, size, spp) for o in VIEWS]
        losses = _fit(scenes, targets, output, iterations, spp, lr, log)
        check = dict(size=size, spp=4 * spp, seed=2000)
        result = {
            "losses": losses,
            "start": image_loss(renders({"type": "brdftab", "source": start}, **check), targets),
            "saved": image_loss(renders({"type": "brdftab", "source": output}, **check), targets),
        }
    if log:
        log(f"image loss of the start table {result['start']:.3e}, of the saved table "
            f"{result['saved']:.3e} ({result['start'] / result['saved']:.1f}x lower)")
    return result


def _fit(scenes, targets, output, iterations, spp, lr, log):
    # One table seen by every view: the optimizer's variable is the values of each scene.
    params = [mi.traverse(s) for s in scenes]
    key = "sphere.bsdf.values"
    opt = mi.ad.Adam(lr=lr)
    opt[key] = params[0][key]
    losses = []
    for it in range(iterations):
        loss = 0.0
        for k, (s, p) in enumerate(zip(scenes, params)):
            p.update(opt)
            img = mi.render(s, p, spp=spp, seed=it * len(VIEWS) + k)
            loss = loss + dr.mean(dr.square(img - targets[k]), axis=None) / len(VIEWS)
        dr.backward(loss)
        losses.append(float(np.array(loss).ravel()[0]))
        opt.step()
        opt[key] = dr.maximum(opt[key], 0.0)  # a BRDF is not negative
        if log:
            log(f"iteration {it:3d}: image loss {losses[-1]:.3e}")
    params[0].update(opt)
    fitted = scenes[0].shapes()[0].bsdf().export_table()
    info = fitted.save(output, codec="f32", replace=True)
    if log:
        log(f"wrote {output} ({info['bytes']} bytes)")
    return losses


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("output", help="the fitted table: a .btdb file or DB#NAME")
    ap.add_argument("--iterations", type=int, default=40)
    ap.add_argument("--size", type=int, default=48, help="image width and height")
    ap.add_argument("--spp", type=int, default=8, help="samples per pixel while fitting")
    args = ap.parse_args(argv)
    optimize(args.output, args.iterations, args.size, args.spp)


if __name__ == "__main__":
    main()
