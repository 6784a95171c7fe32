"""SIGINT latency of long calls (session 42): the time from a SIGINT, sent by a timer thread
DELAY s after the call starts, to its KeyboardInterrupt, and the files the call left.

    python bindings/python/bench/sigint.py CASE DELAY [DELAY ...]

CASE: bake_rgl, convert_btdb, convert_bsdf_aniso, convert_bsdf_iso, fit, cache_lock (a child
process holds the cached table's lock), db_lock (a child holds the lock of the database a bake
into DB#NAME writes). A DELAY past the call's end reports its duration.
"""
import os, pathlib, signal, sys, threading, time, tempfile, subprocess
import brdftab
# A shell's background job starts with SIGINT ignored; Python then installs no handler.
signal.signal(signal.SIGINT, signal.default_int_handler)
D = str(pathlib.Path(__file__).resolve().parents[3] / "data" / "rgl") + "/"
tmp = tempfile.mkdtemp(prefix="sigint")
WARD = '{"model": "ward", "alpha_x": 0.1, "alpha_y": 0.3, "ks": 0.5}'
def out(n): return os.path.join(tmp, n)
CASES = {
    # an RGL bake: adaptive grid (warp fit), error-target search, albedo calibration
    "bake_rgl": lambda: brdftab.bake(D + "satin_rosaline_rgb.bsdf", out("a.btdb")),
    # convert to a table: the bake, then the accuracy report of 200k pairs against the file
    "convert_btdb": lambda: brdftab.convert(D + "satin_rosaline_rgb.bsdf", out("b.btdb"), pairs=2_000_000),
    # .bsdf writer, anisotropic source (azimuths::place, values), then its report
    "convert_bsdf_aniso": lambda: brdftab.convert(WARD, out("c.bsdf")),
    "convert_bsdf_iso": lambda: brdftab.convert(D + "satin_rosaline_rgb.bsdf", out("d.bsdf"), resolution=48),
    "fit": lambda: brdftab.fit(D + "satin_rosaline_rgb.bsdf", "ggx"),
    "cache_lock": None,
    "db_lock": None,
}
def cache_lock():
    cd = out("cache")
    spec = '{"model": "lambert", "kd": 0.5}'
    # the key file name: bake once into another dir to learn it
    r = brdftab.bake_cached(spec, cache_dir=out("probe"), preset="small")
    name = os.path.basename(r["path"])
    os.makedirs(cd, exist_ok=True)
    lp = os.path.join(cd, "." + name + ".lock")
    holder = subprocess.Popen([sys.executable, "-c",
        "import fcntl,sys,time; f=open(sys.argv[1],'a'); fcntl.flock(f, fcntl.LOCK_EX); print('held', flush=True); time.sleep(600)", lp],
        stdout=subprocess.PIPE)
    holder.stdout.readline()
    try:
        return brdftab.bake_cached(spec, cache_dir=cd, preset="small")
    finally:
        holder.kill(); holder.wait()
CASES["cache_lock"] = cache_lock
def hold(lock_path):
    """A child process holding the writer lock `lock_path` (as another writer would)."""
    holder = subprocess.Popen([sys.executable, "-c",
        "import fcntl,sys,time; f=open(sys.argv[1],'a'); fcntl.flock(f, fcntl.LOCK_EX); print('held', flush=True); time.sleep(600)", lock_path],
        stdout=subprocess.PIPE)
    holder.stdout.readline()
    return holder
def db_lock():
    # another writer's streamed bake into the same database holds its lock for the whole bake
    holder = hold(out(".lib.btdb.lock"))
    try:
        return brdftab.bake('{"model": "lambert", "kd": 0.5}', out("lib.btdb") + "#lambert", preset="small")
    finally:
        holder.kill(); holder.wait()
CASES["db_lock"] = db_lock
case = sys.argv[1]
for d in map(float, sys.argv[2:]):
    sent = [None]
    def kill():
        sent[0] = time.perf_counter(); os.kill(os.getpid(), signal.SIGINT)
    for f in os.listdir(tmp):
        p = os.path.join(tmp, f)
        if os.path.isfile(p): os.remove(p)
    t0 = time.perf_counter()
    tm = threading.Timer(d, kill); tm.start()
    try:
        CASES[case]()
        t1 = time.perf_counter(); tm.cancel()
        print(f"{case} delay {d:.1f}s: finished in {t1-t0:.2f}s before the signal", flush=True)
        continue
    except KeyboardInterrupt:
        tm.cancel()
        t1 = time.perf_counter()
    except Exception:
        tm.cancel()
        raise
    left = [f for f in os.listdir(tmp) if os.path.isfile(os.path.join(tmp, f))]
    print(f"{case} delay {d:.1f}s: KeyboardInterrupt {t1-sent[0]:.3f}s after SIGINT (total {t1-t0:.2f}s) files left {left}", flush=True)
