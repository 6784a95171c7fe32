"""Shared fixtures: the repository's paths, the measured RGL files, the `brdftab` CLI."""

import os
import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


def unavailable(why):
    """A prerequisite is missing: a skip on a developer's machine, a failure in CI (`CI` set),
    where every prerequisite is installed by .ci/run and a skip would hide a broken install."""
    if os.environ.get("CI"):
        pytest.fail(f"CI: {why}", pytrace=False)  # noqa: PT016
    pytest.skip(why, allow_module_level=True)


def rgl_dir():
    """The RGL-EPFL files: $BRDFTAB_RGL_DIR, the repository's data/rgl, or ../shared's copy."""
    for d in [os.environ.get("BRDFTAB_RGL_DIR"), ROOT / "data" / "rgl",
              ROOT.parent / "shared" / "data" / "measured" / "rgl"]:
        if d and pathlib.Path(d, "paper_white_rgb.bsdf").is_file():
            return pathlib.Path(d)
    return None


def cli_path():
    """The `brdftab` binary: $BRDFTAB_BIN, target/release or target/debug, or the PATH."""
    for p in [os.environ.get("BRDFTAB_BIN"), ROOT / "target" / "release" / "brdftab",
              ROOT / "target" / "debug" / "brdftab", shutil.which("brdftab")]:
        if p and pathlib.Path(p).is_file():
            return str(p)
    return None


@pytest.fixture(scope="session")
def rgl():
    d = rgl_dir()
    if d is None:
        unavailable("no RGL files (data/rgl or ../shared/data/measured/rgl)")
    return d


@pytest.fixture(scope="session")
def paper(rgl):
    return str(rgl / "paper_white_rgb.bsdf")


@pytest.fixture(scope="session")
def cli():
    p = cli_path()
    if p is None:
        unavailable("no brdftab binary (cargo build --release)")

    def run(*args, stdin=None):
        r = subprocess.run([p, *args], input=stdin, capture_output=True, text=True, timeout=600)
        if r.returncode != 0:
            raise RuntimeError(f"brdftab {' '.join(args)}: {r.stderr}")
        return r.stdout

    return run


@pytest.fixture(autouse=True, scope="session")
def _cache_dir(tmp_path_factory):
    """The cache of baked tables (brdftab.bake_cached, the Mitsuba plugin) in a temporary
    directory: tests never write to the user's ~/.cache."""
    old = os.environ.get("BRDFTAB_CACHE_DIR")
    os.environ["BRDFTAB_CACHE_DIR"] = str(tmp_path_factory.mktemp("bake-cache"))
    yield
    if old is None:
        os.environ.pop("BRDFTAB_CACHE_DIR", None)
    else:
        os.environ["BRDFTAB_CACHE_DIR"] = old
