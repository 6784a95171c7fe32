"""Concurrent use from Python: one table evaluated and sampled from many threads (the calls
release the GIL) as from one; processes adding to one Database at once, some through a
symbolic link to it, lose no table; a reader process sees whole states only; calls that read
or write files release the GIL."""

import multiprocessing
import os
import subprocess
import sys
import threading
import time

import numpy as np

import brdftab

SPEC = '{"model": "ggx", "alpha": 0.3}'


def test_one_table_from_many_threads_as_from_one(tmp_path):
    db = brdftab.Database(tmp_path / "m.btdb")
    db.add(SPEC, "ggx", preset="small")
    lazy = db.open("ggx", eager=False)  # chunks decoded by whichever thread needs them first
    ref = db.open("ggx")
    rng = np.random.default_rng(3)
    wi = rng.normal(size=(5000, 3))
    wo = rng.normal(size=(5000, 3))
    wi[:, 2] = abs(wi[:, 2]) + 0.1
    wo[:, 2] = abs(wo[:, 2]) + 0.1
    u = rng.random((5000, 2))
    want = [ref.eval(wi, wo), ref.pdf(wi, wo), *ref.sample(wo, u)]
    assert want[0].max() > 0
    got, errors = [], []

    def work():
        try:
            got.append([lazy.eval(wi, wo), lazy.pdf(wi, wo), *lazy.sample(wo, u)])
            got.append([np.array([lazy.eval(wi[k], wo[k]) for k in range(300)])])
        except Exception as e:  # noqa: BLE001 - reported below
            errors.append(e)

    threads = [threading.Thread(target=work) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    assert len(got) == 16
    for g in got:
        if len(g) == 1:
            np.testing.assert_array_equal(g[0], want[0][:300])
        else:
            for a, b in zip(g, want):
                np.testing.assert_array_equal(a, b)


def _add(args):
    path, k = args
    db = brdftab.Database(path)
    for i in range(3):
        db.add('{"model": "lambert", "kd": 0.5}', f"p{k}_{i}", preset="small")
    return k


def _read(path):
    """Opens the database until told to stop: every state whole (each table opens eagerly,
    checksums checked), never fewer tables than before."""
    seen, rounds = 0, 0
    while not os.path.exists(path + ".stop"):
        names = brdftab.Database(path).names()
        assert len(names) >= seen, (seen, names)
        seen = len(names)
        brdftab.open(f"{path}#base")
        rounds += 1
    return rounds


def test_processes_adding_at_once_lose_no_table(tmp_path):
    path = str(tmp_path / "db.btdb")
    brdftab.Database(path).add('{"model": "lambert", "kd": 0.2}', "base", preset="small")
    link = str(tmp_path / "link.btdb")
    os.symlink("db.btdb", link)
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(5) as pool:
        reader = pool.apply_async(_read, (path,))
        pool.map(_add, [(path if k % 2 == 0 else link, k) for k in range(4)])
        open(path + ".stop", "w").close()
        assert reader.get(timeout=120) >= 1
    want = {"base"} | {f"p{k}_{i}" for k in range(4) for i in range(3)}
    assert set(brdftab.Database(path).names()) == want
    assert os.path.islink(link), "the link still names the database"


def _runs_beside_other_threads(call, repeat=3):
    """Whether another Python thread runs while `call` does: a ticker thread's timestamps
    inside each call's middle half (a call holding the GIL lets none through)."""
    ticks, stop = [], threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.002)

    t = threading.Thread(target=tick)
    t.start()
    spans = []
    try:
        time.sleep(0.02)
        for _ in range(repeat):
            t0 = time.perf_counter()
            call()
            spans.append((t0, time.perf_counter()))
    finally:
        stop.set()
        t.join()
    inside = [sum(a + (b - a) / 4 < x < b - (b - a) / 4 for x in ticks) for a, b in spans]
    return inside, [round((b - a) * 1000) for a, b in spans]


def test_opening_and_describing_a_table_release_the_gil(tmp_path):
    """`open` (an eager table decodes every chunk) and `info` read the file without the GIL:
    another thread runs meanwhile. (They held it: a medium preset's table froze every other
    thread for 0.16 s per open and 0.19 s per info, a large one's for 0.5 s and 1.4 s.)"""
    path = str(tmp_path / "m.btdb")
    brdftab.bake(SPEC, path, preset="medium")
    for name, call in [("open", lambda: brdftab.open(path)), ("info", lambda: brdftab.info(path)),
                       ("check", lambda: brdftab.check(path))]:
        inside, ms = _runs_beside_other_threads(call)
        assert all(k > 0 for k in inside), f"{name}: no other thread ran during calls of {ms} ms"


def test_a_tables_node_coordinates_and_lookup_copy_release_the_gil(tmp_path):
    """`Table.node_angles`, `Table.node_directions` and `Table.open` (which copies the values)
    run without the GIL (they held it: a large preset's table froze every other thread for
    1.1 s, 1.8 s and 0.26 s)."""
    path = str(tmp_path / "m.btdb")
    brdftab.bake(SPEC, path, preset="medium")
    table = brdftab.open(path).table()
    for name, call in [("node_angles", table.node_angles),
                       ("node_directions", table.node_directions)]:
        inside, ms = _runs_beside_other_threads(call)
        assert all(k > 0 for k in inside), f"{name}: no other thread ran during calls of {ms} ms"
    # A shorter call (tens of ms): some of five let the ticker in (none while the GIL was held).
    inside, ms = _runs_beside_other_threads(table.open, repeat=5)
    assert sum(inside) > 0, f"open: no other thread ran during calls of {ms} ms"


def test_ctrl_c_stops_every_wait_for_a_database_lock(tmp_path):
    """Another writer holds the database's lock (a streamed bake into the same database holds
    it for its whole bake): a bake into ``DB#NAME``, ``Table.save`` into one, and
    ``Database.remove``, ``rename`` and ``add_bytes`` wait for it, and Ctrl-C stops each wait
    (they waited until the lock was free, Ctrl-C pending), leaving the database as it was. In a
    child process, which holds the lock itself and would hang on the old code."""
    one = tmp_path / "one.btdb"
    brdftab.bake('{"model": "lambert", "kd": 0.5}', str(one), preset="small")
    path = tmp_path / "m.btdb"
    db = brdftab.Database(path)
    db.add_bytes("a", one.read_bytes())
    calls = {
        "bake": f"brdftab.bake(SPEC, {str(path) + '#b'!r}, preset='small')",
        "save": f"brdftab.open({str(one)!r}).table().save({str(path) + '#c'!r})",
        "remove": "db.remove('a')",
        "rename": "db.rename('a', 'z')",
        "add_bytes": f"db.add_bytes('d', open({str(one)!r}, 'rb').read())",
    }
    code = f"""
import fcntl, os, signal, sys, threading, time, brdftab
signal.signal(signal.SIGINT, signal.default_int_handler)  # a background job's child ignores it
SPEC = '{{"model": "lambert", "kd": 0.5}}'
db = brdftab.Database({str(path)!r})
lock = open({str(tmp_path / ".m.btdb.lock")!r}, "w")
fcntl.flock(lock, fcntl.LOCK_EX)   # another writer's turn, never ended
for name, call in {calls!r}.items():
    threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
    t0 = time.perf_counter()
    try:
        exec(call)
        print(name, "returned", flush=True)
    except KeyboardInterrupt:
        print(name, "interrupted", round(time.perf_counter() - t0, 3), flush=True)
"""
    before = path.read_bytes()
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           timeout=60)
    except subprocess.TimeoutExpired as e:
        raise AssertionError(f"a wait for the lock did not stop: {e.stdout}") from None
    lines = [l.split() for l in r.stdout.splitlines()]
    assert [l[:2] for l in lines] == [[n, "interrupted"] for n in calls], r.stdout + r.stderr
    # Within a few of the 50 ms polls after the signal (0.3 s), not at a lock's release.
    assert all(float(l[2]) < 5.0 for l in lines), r.stdout
    assert path.read_bytes() == before
    assert db.names() == ["a"]


def test_listing_and_removing_tables_release_the_gil(tmp_path):
    """`Database.names` (and so `in`, `len` and iteration) reads the table of contents without
    the GIL: another thread runs meanwhile. (It held it, reading every table's header too: 30 ms
    a call for 20 tables of 200 kB names, 0.27 s for 5,000 tables of short ones.)
    `Database.remove` waits for the database's lock without it: a thread of the process that
    holds the lock finishes its turn (it could not run: a deadlock)."""
    one = tmp_path / "one.btdb"
    brdftab.bake('{"model": "lambert", "kd": 0.5}', str(one), preset="small")
    data = one.read_bytes()
    path = tmp_path / "m.btdb"
    db = brdftab.Database(path)
    for i in range(20):
        db.add_bytes(f"{i:03d}" + "x" * 200_000, data)
    # Calls of ten milliseconds or so: some of ten let the ticker in (none while it was held).
    inside, ms = _runs_beside_other_threads(db.names, repeat=10)
    assert sum(inside) > 0, f"names: no other thread ran during calls of {ms} ms"
    # Another writer's turn (the lock `brdftab` takes: flock on .NAME.lock beside the file),
    # ended by a thread of this process while `remove` waits; in a child, which could hang.
    code = f"""
import fcntl, threading, time, brdftab
lock = open({str(tmp_path / ".m.btdb.lock")!r}, "w")
fcntl.flock(lock, fcntl.LOCK_EX)
threading.Thread(target=lambda: (time.sleep(0.2), lock.close()), daemon=True).start()
brdftab.Database({str(path)!r}).remove("000" + "x" * 200_000)
print(len(brdftab.Database({str(path)!r}).names()))
"""
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           timeout=60)
    except subprocess.TimeoutExpired:
        raise AssertionError("remove held the GIL while it waited for the lock") from None
    assert r.stdout.split() == ["19"], r.stdout + r.stderr
    # `Database.rename` (session 41) waits for the lock as `remove` does.
    code = code.replace('.remove("000" + "x" * 200_000)', '.rename("001" + "x" * 200_000, "one")')
    code = code.replace("print(len(", "print(sorted(").replace(".names()))", ".names())[-1])")
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           timeout=60)
    except subprocess.TimeoutExpired:
        raise AssertionError("rename held the GIL while it waited for the lock") from None
    assert r.stdout.split() == ["one"], r.stdout + r.stderr
