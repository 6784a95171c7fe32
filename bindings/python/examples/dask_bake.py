"""Bake a collection of materials on a Dask cluster and gather them into one database.

    python dask_bake.py OUT.btdb [--rgl DIR] [--sweep N] [--preset P] [--scheduler ADDRESS]

Each material is one task: a worker receives the source (an inline model spec, or the bytes
of an RGL/MERL/JSON file, so workers need no shared filesystem), bakes it with
:func:`brdftab.bake` into a temporary file and returns the table file's bytes. The client
adds each result to one database as it arrives (:meth:`brdftab.Database.add_bytes`, which
copies the compressed chunks unchanged). Nothing is lost or duplicated: a task's key is the
table's name, Dask re-runs a task whose worker died (the result is the same table), only the
client writes the database, and an existing name is an error unless ``--replace``.

Without ``--scheduler`` the cluster is a :class:`distributed.LocalCluster` on this machine
(one single-threaded worker process per core; each bake is itself parallel, so this is the
shape that scales to many machines). On a real cluster:

    dask scheduler                                  # on one machine: tcp://HOST:8786
    dask worker tcp://HOST:8786 --nthreads 1        # on each machine (pip install brdftab)
    python dask_bake.py materials.btdb --scheduler tcp://HOST:8786 --rgl /data/rgl

or from a batch system through ``dask-jobqueue`` (``SLURMCluster(...).scale(jobs=N)``) or on
Kubernetes through ``dask-kubernetes``: the client code below is the same, only the cluster
object differs. Workers need ``brdftab`` (the same version: a table records the library that
baked it) and nothing else.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import tempfile

import brdftab


def jobs(rgl_dir=None, sweep=0, preset=None):
    """The (name, source, options) of every table to bake: each RGL file of ``rgl_dir`` and a
    sweep of GGX copper roughness values (a rate–distortion or fitting study's shape)."""
    out = []
    opts = {"preset": preset} if preset else {}
    if rgl_dir:
        for f in sorted(pathlib.Path(rgl_dir).glob("*.bsdf")):
            out.append((f.stem, str(f), dict(opts)))
    for k in range(sweep):
        alpha = round(0.05 + 0.45 * k / max(sweep - 1, 1), 4)
        spec = json.dumps({"model": "ggx", "alpha": alpha, "fresnel": {"conductor": "Cu"}})
        out.append((f"ggx_cu_{alpha:g}", spec, {"preset": preset or "small"}))
    names = [n for n, _, _ in out]
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate table names in the job list: {names}")
    return out


def payload(source):
    """What a worker needs to open SOURCE anywhere: the text of an inline spec, or the file's
    name and bytes."""
    if source.lstrip().startswith("{"):
        return {"spec": source}
    p = pathlib.Path(source)
    return {"file": p.name, "bytes": p.read_bytes()}


def bake_task(what, options):
    """Runs on a worker: bakes the source described by ``payload`` and returns the table
    file's bytes."""
    with tempfile.TemporaryDirectory() as d:
        if "spec" in what:
            source = what["spec"]
        else:
            source = os.path.join(d, what["file"])
            with open(source, "wb") as f:
                f.write(what["bytes"])
        out = os.path.join(d, "table.btdb")
        brdftab.bake(source, out, **options)
        with open(out, "rb") as f:
            return f.read()


def bake_all(client, job_list, database, replace=False):
    """Submits every job to ``client`` and adds each table to ``database`` (a path) as it
    arrives. Returns the names added, in completion order."""
    from distributed import as_completed

    db = brdftab.Database(database)
    futures = {}
    for name, source, options in job_list:
        # The key names the table: a result for a name arrives once, whatever the retries.
        f = client.submit(bake_task, payload(source), options, key=f"brdftab-bake-{name}",
                          retries=2)
        futures[f] = name
    added = []
    for f, data in as_completed(futures, with_results=True):
        db.add_bytes(futures[f], data, replace=replace)
        added.append(futures[f])
    missing = {n for n, _, _ in job_list} - set(db.names())
    if missing:
        raise RuntimeError(f"tables missing from {database}: {sorted(missing)}")
    return added


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("database")
    ap.add_argument("--rgl", help="a directory of RGL .bsdf files")
    ap.add_argument("--sweep", type=int, default=0, help="GGX copper roughness values")
    ap.add_argument("--preset", help="bake preset (default: the library's per source)")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler")
    ap.add_argument("--workers", type=int, default=os.cpu_count())
    ap.add_argument("--replace", action="store_true")
    a = ap.parse_args()
    from distributed import Client, LocalCluster

    job_list = jobs(a.rgl, a.sweep, a.preset)
    if a.scheduler:
        client = Client(a.scheduler)
    else:
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    with client:
        added = bake_all(client, job_list, a.database, a.replace)
    print(f"{len(added)} tables in {a.database}: {', '.join(sorted(added))}")


if __name__ == "__main__":
    main()
