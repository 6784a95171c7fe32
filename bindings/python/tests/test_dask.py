"""The distributed bake (issue 26, item 4): the shipped materials and a parameter sweep baked on
a Dask LocalCluster and gathered into one database, nothing lost or duplicated, every table the
one a local bake makes."""

import importlib.util
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import brdftab

from conftest import unavailable

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "dask_bake.py"


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("dask_bake", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def client():
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        unavailable("dask.distributed is not installed (pip install 'dask[distributed]')")
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    with Client(cluster) as c:
        yield c
    cluster.close()


def test_a_local_cluster_bakes_every_material_once(example, client, rgl, tmp_path):
    jobs = example.jobs(rgl, sweep=4, preset="small")
    names = [n for n, _, _ in jobs]
    assert len(names) == 7 + 4
    db = tmp_path / "all.btdb"
    added = example.bake_all(client, jobs, str(db))
    assert sorted(added) == sorted(names)
    d = brdftab.Database(db)
    assert sorted(d.names()) == sorted(names), "each table once"
    rng = np.random.default_rng(1)
    wi = rng.normal(size=(64, 3))
    wi[:, 2] = np.abs(wi[:, 2])
    wo = wi[::-1].copy()
    for name, source, options in [jobs[0], jobs[-1]]:
        local = tmp_path / f"{name}.btdb"
        brdftab.bake(source, str(local), **options)
        np.testing.assert_array_equal(d.open(name).eval(wi, wo),
                                      brdftab.open(str(local)).eval(wi, wo))
    # Gathering again does not duplicate: an existing name is an error unless replace.
    with pytest.raises(brdftab.Error):
        example.bake_all(client, jobs[-1:], str(db))
    example.bake_all(client, jobs[-1:], str(db), replace=True)
    assert sorted(d.names()) == sorted(names)


def test_add_bytes_refuses_a_damaged_table(tmp_path):
    t = tmp_path / "t.btdb"
    brdftab.bake('{"model": "lambert", "kd": 0.5}', str(t), preset="small")
    data = bytearray(t.read_bytes())
    db = brdftab.Database(tmp_path / "db.btdb")
    db.add_bytes("ok", bytes(data))
    data[len(data) // 2] ^= 0x40
    with pytest.raises(brdftab.Error):
        db.add_bytes("bad", bytes(data))
    assert db.names() == ["ok"]
    with pytest.raises(ValueError):
        db.add_bytes("a#b", t.read_bytes())
    # a database of two tables: said in the caller's terms (it was "<bytes> is a database of 2
    # tables; name one as <bytes>#NAME")
    db.add_bytes("ok2", t.read_bytes())
    with pytest.raises((brdftab.Error, ValueError), match="hold 2 tables") as e:
        db.add_bytes("c", (tmp_path / "db.btdb").read_bytes())
    assert "<bytes>" not in str(e.value)


def test_add_bytes_takes_any_buffer_and_refuses_other_types(tmp_path):
    t = tmp_path / "t.btdb"
    brdftab.bake('{"model": "lambert", "kd": 0.5}', str(t), preset="small")
    data = t.read_bytes()
    db = brdftab.Database(tmp_path / "db.btdb")
    db.add_bytes("b", data)
    db.add_bytes("ba", bytearray(data))
    db.add_bytes("mv", memoryview(data))
    db.add_bytes("slice", memoryview(b"xx" + data)[2:])
    assert db.names() == ["b", "ba", "mv", "slice"]
    one = db.open("b").eval([0, 0, 1], [0, 0, 1])
    for n in ["ba", "mv", "slice"]:
        np.testing.assert_array_equal(db.open(n).eval([0, 0, 1], [0, 0, 1]), one)
    for bad in [str(t), len(data), None]:
        with pytest.raises(TypeError):
            db.add_bytes("bad", bad)
    assert db.names() == ["b", "ba", "mv", "slice"]


# Run in a fresh interpreter: ru_maxrss is the process's high-water mark, which a bake in the
# same process would already have raised above what the import needs.
_PEAK = """
import resource, sys
import brdftab
big, small, path = sys.argv[1:4]
data = open(big, "rb").read()
db = brdftab.Database(path)
db.add_bytes("warm", open(small, "rb").read())
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
db.add_bytes("big", data)
print(len(data), (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) * 1024)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ru_maxrss in KiB is Linux's")
def test_add_bytes_reads_bytes_in_place(tmp_path):
    """The bytes were extracted into a Rust Vec: a second copy of the whole table, whose failed
    allocation aborts the interpreter instead of raising MemoryError. Read in place, importing a
    5 MB table raises the peak by the writer's 1 MiB buffer, not by another 5 MB (it was 6.3)."""
    big, small = tmp_path / "big.btdb", tmp_path / "small.btdb"
    brdftab.bake('{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.4}', str(big),
                 grid="48x96x48x96", codec="f32", level=1)
    brdftab.bake('{"model": "lambert", "kd": 0.5}', str(small), preset="small")
    out = subprocess.run([sys.executable, "-c", _PEAK, str(big), str(small),
                          str(tmp_path / "db.btdb")],
                         capture_output=True, text=True, check=True).stdout
    size, growth = map(int, out.split())
    assert size > 4_000_000
    assert growth < size / 2, f"the import of {size} bytes raised the peak by {growth}"
    assert brdftab.Database(tmp_path / "db.btdb").names() == ["warm", "big"]
