"""The Mitsuba plugin's load times with the cache of baked tables, and its render time against
Mitsuba's ``measured`` (issue 26, item 3).

    python bindings/python/bench/plugin_load.py [--file data/rgl/cc_ibiza_sunset_rgb.bsdf]

llvm_ad_rgb (``DRJIT_LIBLLVM_PATH`` set). Loads run in fresh processes, so nothing of an earlier
load is warm but the OS's page cache and the cache directory: the first load (empty cache: the
bake), then three cached loads; ``measured`` loads the RGL file itself. Then one render of the
same scene with each plugin (bench.py's scene, interleaved, best of 4 after a warm-up).
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[3]

LOAD = r"""
import sys, time
import mitsuba as mi, drjit as dr
mi.set_variant("llvm_ad_rgb")
import brdftab.mitsuba
brdftab.mitsuba.register()
kind, f, cache = sys.argv[1:4]
d = ({"type": "brdftab", "source": f, "cache_dir": cache} if kind == "brdftab"
     else {"type": "measured", "filename": f})
t0 = time.perf_counter()
b = mi.load_dict(d)
dr.eval()
dr.sync_thread()
print(time.perf_counter() - t0)
"""


def load(kind, f, cache):
    r = subprocess.run([sys.executable, "-c", LOAD, kind, f, cache], capture_output=True,
                       text=True, check=True)
    return float(r.stdout.split()[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--file", default=str(ROOT / "data" / "rgl" / "cc_ibiza_sunset_rgb.bsdf"))
    ap.add_argument("--no-render", action="store_true")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as cache:
        first = load("brdftab", a.file, cache)
        cached = [load("brdftab", a.file, cache) for _ in range(3)]
        measured = [load("measured", a.file, cache) for _ in range(3)]
        res = {"file": pathlib.Path(a.file).name, "first_load_s": first,
               "cached_load_s": statistics.median(cached), "cached_loads_s": cached,
               "measured_load_s": statistics.median(measured)}
        print(json.dumps(res), flush=True)
        if not a.no_render:
            sys.path.insert(0, str(pathlib.Path(__file__).parent))
            import os

            os.environ["BRDFTAB_CACHE_DIR"] = cache
            import bench

            # The plugin on the file itself (its default table, from the cache) vs measured.
            times, diff = bench.render_times(a.file, a.file, None)
            res["render_s"] = times
            res["render_ratio_plugin_over_measured"] = float(times["plugin"] / times["measured"])
            res["mean_image_difference"] = float(diff)
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
