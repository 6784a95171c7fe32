"""`brdftab render` against Mitsuba 3 on the same scene (session 40).

    python bindings/python/bench/render_vs_mitsuba.py [--brdftab target/release/brdftab]
        [--size 96] [--spp 256] [--mitsuba-spp 1024] [--variant scalar_rgb] [--cases a,b] [--json]

Nobody had compared the preview renderer's images with an independent renderer. This script
rebuilds the scene `brdftab render` draws (tools/brdftab/preview/scene.rs) as a Mitsuba scene:

- camera: pinhole at c + 5.2 · normalize(0, −1, 0.2) looking at the sphere's centre c = (0, 0, 1),
  z up, 28° vertical field of view, box pixel filter (brdftab jitters uniformly in the pixel);
- the unit sphere at c; `--ground`: a diffuse plane z = 0 of albedo 0.5 (brdftab's is infinite,
  Mitsuba's a rectangle of half-size 1000, so the pixels along the horizon differ);
- `--env sky`: brdftab's 512 × 256 lat-long table (row 0 = +z, azimuth from +x towards +y,
  nearest texel) recomputed here from the same formula, upsampled ×8 by repetition so that
  Mitsuba's bilinear lookup reads the same piecewise-constant radiance, with its columns flipped
  and a rotation so that Mitsuba's envmap (y up, u = atan2(x, −z)/2π) sees the same directions;
  `white`: a constant environment of radiance 1;
- `--light point`: an isotropic point light at (−2.5, −2.5, 4) of intensity 15 W/sr;
  `--light area`: an emitting sphere there, radius 0.35, radiance 15/(π 0.35²);
- `--mode lit` is Mitsuba's `path` at max_depth 2; `--mode path --max-depth D` at D + 1
  (brdftab counts surface interactions, Mitsuba path vertices).

Materials with an independent peer: Lambert → `diffuse`; GGX with a complex Fresnel index →
`roughconductor` (Mitsuba's separable Smith G1·G1 against brdftab's height-correlated G2: a
difference by design, below 0.1 % of the mean at α = 0.1); an RGL file → Mitsuba's `measured`
on the same file (paper_white: no negative values in its tensor, see fidelity.py).

Each row compares the linear images (brdftab's f32 EXR against Mitsuba's film, each the mean of
two seeds): the ratio of the means per channel with its standard error, and the
relative RMSE sqrt(Σ(a − b)²/Σb²) next to the noise it would have if the two renderers agreed
(each renderer's own noise, from the relative RMSE between its two seeds, added in quadrature).
Renderers that agree show mean ratios within a few standard errors of 1 and a relative RMSE at
the noise.
"""

import argparse
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[3]

EYE_DIR = np.array([0.0, -1.0, 0.2]) / math.sqrt(1.04)
CENTER = np.array([0.0, 0.0, 1.0])
EYE = CENTER + 5.2 * EYE_DIR
LIGHT_POS = [-2.5, -2.5, 4.0]


def sky_texels(w=512, h=256):
    """brdftab's default sky (scene.rs `Environment::sky`): linear RGB, row 0 = zenith."""
    sun = np.array([-0.55, -0.75, 0.83])
    sun /= np.linalg.norm(sun)
    theta = np.pi * (np.arange(h) + 0.5) / h
    phi = 2 * np.pi * (np.arange(w) + 0.5) / w
    t, p = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1)
    zenith, horizon, ground = (np.array(v) for v in
                               ([0.30, 0.50, 0.95], [0.95, 0.97, 1.0], [0.16, 0.14, 0.12]))
    up = np.maximum(d[..., 2], 0.0)[..., None]
    sky = horizon + (zenith - horizon) * np.sqrt(up)
    tt = np.clip(-d[..., 2] / 0.08, 0.0, 1.0)[..., None]
    tt = tt * tt * (3.0 - 2.0 * tt)
    base = sky + (ground - sky) * tt
    cos_g = d @ sun
    sun_l = 6.0 * np.exp(30.0 * (cos_g - 1.0))[..., None] * np.array([1.0, 0.92, 0.80])
    return (base + sun_l * (1.0 - tt)).astype(np.float32)


def mitsuba_scene(mi, bsdf, size, env, light, ground, depth):
    T = mi.ScalarTransform4f
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": depth + 1},
        "sensor": {"type": "perspective", "fov": 28, "fov_axis": "y",
                   "to_world": T().look_at(EYE.tolist(), CENTER.tolist(), [0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": size, "height": size,
                            "pixel_format": "rgb", "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent"}},
        "sphere": {"type": "sphere", "center": CENTER.tolist(), "radius": 1.0, "bsdf": bsdf},
    }
    if ground:
        # Half-size 1000: larger planes lose Mitsuba's f32 precision (at 1e5 the point-lit
        # ground came out 0.2 % darker); within 0.12° below the horizon it shows the sky.
        scene["ground"] = {"type": "rectangle", "to_world": T().scale([1e3, 1e3, 1.0]),
                           "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb",
                                                                        "value": 0.5}}}
    if env == "sky":
        # Columns flipped: Mitsuba's u runs the other way round the axis; repetition ×8 makes
        # its bilinear filter a nearest lookup but within 1/16 texel of the texel edges.
        tex = np.repeat(np.repeat(sky_texels()[:, ::-1], 8, 0), 8, 1)
        # Mitsuba's envmap frame (x, y, z) = world (−y, z, −x): to_world maps local → world.
        m = [[0, 0, -1, 0], [-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1]]
        scene["env"] = {"type": "envmap", "bitmap": mi.Bitmap(np.ascontiguousarray(tex)),
                        "to_world": T(m)}
    elif env == "white":
        scene["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}}
    if light == "point":
        scene["light"] = {"type": "point", "position": LIGHT_POS,
                          "intensity": {"type": "rgb", "value": 15.0}}
    elif light == "area":
        r = 0.35
        scene["light"] = {"type": "sphere", "center": LIGHT_POS, "radius": r,
                          "emitter": {"type": "area", "radiance": {
                              "type": "rgb", "value": 15.0 / (math.pi * r * r)}}}
    return mi.load_dict(scene)


# (name, brdftab SOURCE, Mitsuba BSDF dict, env, light, ground, mode, depth)
GGX_N = [0.27, 0.68, 1.32]
GGX_K = [3.61, 2.63, 2.29]
# brdftab's Lambert k_d is the BRDF value (albedo π k_d); Mitsuba's reflectance is the albedo.
ALBEDO = [0.8, 0.5, 0.2]
LAMBERT = (json.dumps({"model": "lambert", "kd": [a / math.pi for a in ALBEDO]}),
           {"type": "diffuse", "reflectance": {"type": "rgb", "value": ALBEDO}})
GGX = (json.dumps({"model": "ggx", "alpha": 0.1, "fresnel": {"n": GGX_N, "k": GGX_K}}),
       {"type": "roughconductor", "distribution": "ggx", "alpha": 0.1,
        "eta": {"type": "rgb", "value": GGX_N}, "k": {"type": "rgb", "value": GGX_K}})
PAPER = str(ROOT / "data/rgl/paper_white_rgb.bsdf")
MEASURED = (PAPER, {"type": "measured", "filename": PAPER})

CASES = {
    "lambert-point-lit": (*LAMBERT, "none", "point", False, "lit", 1),
    "lambert-area-lit": (*LAMBERT, "none", "area", False, "lit", 1),
    "lambert-white-lit": (*LAMBERT, "white", "none", False, "lit", 1),
    "lambert-sky-lit": (*LAMBERT, "sky", "none", False, "lit", 1),
    "lambert-sky-ground-path": (*LAMBERT, "sky", "none", True, "path", 8),
    "lambert-point-ground-path": (*LAMBERT, "none", "point", True, "path", 8),
    "ggx-sky-lit": (*GGX, "sky", "none", False, "lit", 1),
    "ggx-area-lit": (*GGX, "none", "area", False, "lit", 1),
    "paper-sky-lit": (*MEASURED, "sky", "none", False, "lit", 1),
}


def brdftab_render(exe, source, size, spp, env, light, ground, mode, depth, out, seed):
    cmd = [exe, "render", source, "-o", str(out), "--size", f"{size}x{size}", "--spp", str(spp),
           "--env", env, "--light", light, "--mode", mode, "--seed", str(seed)]
    if mode == "path":
        cmd += ["--max-depth", str(depth)]
    if ground:
        cmd.append("--ground")
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: {r.stderr}")


def render_exr(mi, exe, case, size, spp, out, seed):
    """brdftab's linear image of `case` under `seed`."""
    source, _, env, light, ground, mode, depth = case
    brdftab_render(exe, source, size, spp, env, light, ground, mode, depth, out, seed)
    return np.array(mi.Bitmap(str(out)), dtype=np.float64)[..., :3]


def interior(size):
    """Pixels whose four corners all see the sphere (scene.rs's camera): no silhouette, where
    the two renderers' anti-aliasing may part."""
    fwd = (CENTER - EYE) / np.linalg.norm(CENTER - EYE)
    right = np.cross(fwd, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    t = math.tan(math.radians(14.0))
    s = np.arange(size + 1) / size
    px, py = np.meshgrid((2 * s - 1) * t, (1 - 2 * s) * t)
    d = fwd + px[..., None] * right + py[..., None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    oc = EYE - CENTER
    b = d @ oc
    hit = b * b - (oc @ oc - 1.0) > 0
    return hit[:-1, :-1] & hit[1:, :-1] & hit[:-1, 1:] & hit[1:, 1:]


def stats(a, b):
    d2 = ((a - b) ** 2).sum()
    return {"rel_rmse": float(math.sqrt(d2 / (b * b).sum())),
            "mean_ratio": [float(a[..., c].mean() / b[..., c].mean()) for c in range(3)]}


def compare_case(mi, exe, name, size, spp, mitsuba_spp, keep=None):
    """One row: brdftab's and Mitsuba's renders of case `name`, each the mean of seeds 0 and 1."""
    case = CASES[name]
    _, bsdf, env, light, ground, _, depth = case
    with tempfile.TemporaryDirectory() as tmp:
        a0, a1 = (render_exr(mi, exe, case, size, spp, pathlib.Path(tmp) / f"{seed}.exr", seed)
                  for seed in (0, 1))
    scene = mitsuba_scene(mi, bsdf, size, env, light, ground, depth)
    m0, m1 = (np.array(mi.render(scene, spp=mitsuba_spp, seed=seed), dtype=np.float64)
              for seed in (0, 1))
    a, m = 0.5 * (a0 + a1), 0.5 * (m0 + m1)
    if keep:
        np.save(pathlib.Path(keep) / f"{name}-brdftab.npy", a)
        np.save(pathlib.Path(keep) / f"{name}-mitsuba.npy", m)
    # The noise of each averaged image: half the relative RMSE of its two seeds.
    noise = math.hypot(stats(m0, m1)["rel_rmse"], stats(a0, a1)["rel_rmse"]) / 2
    # Standard error of the ratio of the image means, from each renderer's two seeds.
    se = [float(math.hypot(np.std(m0[..., c] - m1[..., c]), np.std(a0[..., c] - a1[..., c]))
                / 2 / math.sqrt(m0[..., c].size) / m[..., c].mean()) for c in range(3)]
    # The same over the sphere's interior pixels.
    k = interior(size)
    ratio_in = [float(a[k, c].sum() / m[k, c].sum()) for c in range(3)]
    se_in = [float(math.hypot(np.std(m0[k, c] - m1[k, c]), np.std(a0[k, c] - a1[k, c]))
                   / 2 / math.sqrt(k.sum()) / m[k, c].mean()) for c in range(3)]
    return {"case": name, **stats(a, m), "noise": noise, "mean_se": se,
            "interior_ratio": ratio_in, "interior_se": se_in}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--brdftab", default=os.environ.get("BRDFTAB_BIN",
                                                        str(ROOT / "target/release/brdftab")))
    ap.add_argument("--size", type=int, default=96)
    ap.add_argument("--spp", type=int, default=256, help="brdftab's samples per pixel")
    ap.add_argument("--mitsuba-spp", type=int, default=1024)
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    import mitsuba as mi
    mi.set_variant(args.variant)
    rows = []
    for name in args.cases.split(","):
        row = compare_case(mi, args.brdftab, name, args.size, args.spp, args.mitsuba_spp,
                           os.environ.get("RVM_KEEP"))
        rows.append(row)
        if not args.json:
            ratio = " ".join(f"{r:.4f}" for r in row["mean_ratio"])
            inner = " ".join(f"{r:.4f}" for r in row["interior_ratio"])
            print(f"{name:26} mean ratio R G B {ratio} (±{max(row['mean_se']):.4f}), sphere "
                  f"interior {inner} (±{max(row['interior_se']):.4f}); rel RMSE "
                  f"{100 * row['rel_rmse']:.2f} % (noise {100 * row['noise']:.2f} %)", flush=True)
    if args.json:
        json.dump(rows, sys.stdout, indent=1)


if __name__ == "__main__":
    main()
