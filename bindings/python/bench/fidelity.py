"""Render-level fidelity of the Mitsuba plugin against Mitsuba's own ``measured`` (issue 22).

    python bindings/python/bench/fidelity.py [--files data/rgl/*.bsdf] [--quick] [--json]

What a user compares: the same RGL file rendered by Mitsuba's ``measured`` plugin and by the
``brdftab`` plugin on its default table (llvm_ad_rgb; ``DRJIT_LIBLLVM_PATH`` set), in the scenes
issue 22 named — a sphere under a constant environment, a sphere lit from the side by a
directional light (the terminator), a plane lit 10° above the horizon, a plane seen along its
normal under a constant environment (the viewer's albedo at θo = 0) — and in the ones the
table's metrics weigh least: a plane seen 10° above the horizon, lit at 45° or at 10° (both
directions in the grazing band). Each row is the relative difference of the image means per
channel (brdftab − measured) / measured.

A channel in which the file itself holds negative values (the RGB tensors of some RGL files,
converted from spectra, dip below 0 in dark channels: ``negative_channels``) is not compared:
``measured`` interpolates and renders them as they are, negative radiance included, while
brdftab clips each evaluation at 0 as the reference reader (powitacq) does, so the two differ
there by design (``n/a`` in the table).

The scene builders and :func:`negative_channels` are imported by ``tests/test_mitsuba.py``,
which pins the issue's scenes.
"""

import argparse
import json
import math
import pathlib
import struct

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[3]


def _transform(mi):
    return mi.ScalarTransform4f


def _film(size):
    return {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}}


def sphere_env(mi, bsdf, size=64):
    """A sphere under a constant environment of radiance 1 (one bounce)."""
    T = _transform(mi)
    return mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 24,
                   "to_world": T().look_at([0, -5, 0], [0, 0, 0], [0, 0, 1]),
                   "film": _film(size), "sampler": {"type": "independent"}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}}})


def sphere_sun(mi, bsdf, size=128, direction=(1.0, 1.0, 0.0)):
    """A sphere lit by a directional light travelling along `direction`, seen from −y: with
    (1, 1, 0) the light comes from the viewer's left and behind, so the terminator crosses
    the sphere's face. Direct light by emitter sampling only (no BSDF sampling, no noise but
    the pixel jitter)."""
    T = _transform(mi)
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
        "sensor": {"type": "perspective", "fov": 24,
                   "to_world": T().look_at([0, -5, 0], [0, 0, 0], [0, 0, 1]),
                   "film": _film(size), "sampler": {"type": "independent"}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "sun": {"type": "directional", "direction": list(direction),
                "irradiance": {"type": "rgb", "value": 1.0}}})


def plane_sun(mi, bsdf, light_elev_deg, cam_elev_deg, size=32):
    """A plane (z = 0) lit by a directional light `light_elev_deg` above the horizon from +x,
    seen from −y `cam_elev_deg` above the horizon through a narrow (10°) field of view: the
    image is f_r cos θ of nearly one pair of directions, 90° apart in azimuth."""
    T = _transform(mi)
    le, ce = math.radians(light_elev_deg), math.radians(cam_elev_deg)
    cam = [0.0, -6 * math.cos(ce), 6 * math.sin(ce)]
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
        "sensor": {"type": "perspective", "fov": 10,
                   "to_world": T().look_at(cam, [0, 0, 0], [0, 0, 1]),
                   "film": _film(size), "sampler": {"type": "independent"}},
        "plane": {"type": "rectangle", "to_world": T().scale(4.0), "bsdf": bsdf},
        "sun": {"type": "directional", "direction": [-math.cos(le), 0.0, -math.sin(le)],
                "irradiance": {"type": "rgb", "value": 1.0}}})


def normal_view(mi, bsdf, size=8):
    """A plane seen straight down its normal (2° field of view) under a constant environment:
    each pixel is the viewer's directional albedo at θo ≈ 0."""
    T = _transform(mi)
    return mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 2,
                   "to_world": T().look_at([0, 0, 10], [0, 0, 0], [0, 1, 0]),
                   "film": _film(size), "sampler": {"type": "independent"}},
        "plane": {"type": "rectangle", "to_world": T().scale(10.0), "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}}})


#: (name, scene builder taking (mi, bsdf), samples per pixel, the issue's bar for it): the
#: environment scenes integrate f_r over one direction (the albedo: 1 %), the sphere lit by the
#: sun and the plane at 45° sample pairs within 80° (1 %), the grazing scenes a direction past
#: 80° (the grazing band: 3 %). The issue's own scenes come first.
SCENES = [
    ("sphere_env", lambda mi, b: sphere_env(mi, b), 1024, 0.01),
    ("sphere_terminator", lambda mi, b: sphere_sun(mi, b), 32, 0.01),
    ("plane_light10_view45", lambda mi, b: plane_sun(mi, b, 10, 45), 64, 0.03),
    ("normal_view_env", lambda mi, b: normal_view(mi, b), 8192, 0.01),
    ("plane_light45_view10", lambda mi, b: plane_sun(mi, b, 45, 10), 64, 0.03),
    ("plane_light10_view10", lambda mi, b: plane_sun(mi, b, 10, 10), 64, 0.03),
]


def negative_channels(path):
    """The RGB channels (0, 1, 2) in which the RGL file's `rgb` tensor holds negative values,
    read from the tensor file itself (header: magic, version, field count; per field its name,
    rank, dtype, offset and shape)."""
    b = pathlib.Path(path).read_bytes()
    if b[:12] != b"tensor_file\0":
        raise ValueError(f"{path}: not an RGL tensor file")
    dtypes = {1: np.uint8, 2: np.int8, 3: np.uint16, 4: np.int16, 5: np.uint32, 6: np.int32,
              7: np.uint64, 8: np.int64, 9: np.float16, 10: np.float32, 11: np.float64}
    (count,) = struct.unpack_from("<I", b, 14)
    p = 18
    for _ in range(count):
        (n,) = struct.unpack_from("<H", b, p)
        name = b[p + 2:p + 2 + n].decode()
        p += 2 + n
        rank, dtype, offset = struct.unpack_from("<HBQ", b, p)
        p += 11
        shape = struct.unpack_from("<" + "Q" * rank, b, p)
        p += 8 * rank
        if name == "rgb":
            a = np.frombuffer(b, dtypes[dtype], int(np.prod(shape)), offset).reshape(shape)
            # (φi, θi, channel, u, v)
            return [c for c in range(shape[2]) if (a[:, :, c] < 0).any()]
    return []


def image_mean(mi, scene, spp, seed):
    return np.array(mi.render(scene, spp=spp, seed=seed)).reshape(-1, 3).mean(0)


def compare(mi, path, scenes=SCENES, spp_scale=1.0):
    """Rows {scene, rel: per-channel relative difference (None where not compared), bar, ok}."""
    ours = {"type": "brdftab", "source": str(path)}
    ref = {"type": "measured", "filename": str(path)}
    skip = negative_channels(path)
    rows = []
    for name, build, spp, bar in scenes:
        n = max(1, int(spp * spp_scale))
        a = image_mean(mi, build(mi, ours), n, 1)
        b = image_mean(mi, build(mi, ref), n, 2)
        rel = [None if c in skip else float((a[c] - b[c]) / b[c]) for c in range(3)]
        ok = all(r is None or abs(r) <= bar for r in rel)
        rows.append({"scene": name, "rel": rel, "bar": bar, "ok": ok,
                     "brdftab": a.tolist(), "measured": b.tolist()})
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--files", nargs="*",
                    default=sorted(str(p) for p in (ROOT / "data" / "rgl").glob("*.bsdf")))
    ap.add_argument("--quick", action="store_true", help="a quarter of the samples")
    ap.add_argument("--json", action="store_true", help="one JSON object per row")
    a = ap.parse_args()
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import brdftab.mitsuba

    brdftab.mitsuba.register()
    print("| file | " + " | ".join(s[0] for s in SCENES) + " |")
    print("|---" * (len(SCENES) + 1) + "|")
    for f in a.files:
        rows = compare(mi, f, spp_scale=0.25 if a.quick else 1.0)
        if a.json:
            for r in rows:
                print(json.dumps({"file": pathlib.Path(f).name, **r}), flush=True)
            continue
        cells = []
        for r in rows:
            rel = " / ".join("n/a" if x is None else f"{100 * x:+.2f}" for x in r["rel"])
            cells.append(rel + ("" if r["ok"] else " (!)"))
        print(f"| {pathlib.Path(f).stem} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
