"""The package's README (bindings/python/README.md, its PyPI page) and the repository's as a new
user reads them: every Python block runs as written, from a directory laid out as the
repository's root."""

import os
import re

import numpy as np
import pytest

from conftest import ROOT, unavailable

README = ROOT / "bindings" / "python" / "README.md"


def blocks(readme=README):
    """A README's ```python blocks, in order."""
    return re.findall(r"^```python\n(.*?)^```", readme.read_text(encoding="utf-8"), re.M | re.S)


@pytest.fixture
def repo_root(tmp_path, rgl, monkeypatch):
    """A working directory with data/rgl (the shipped files) and a cache of its own."""
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "rgl").symlink_to(rgl, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("BRDFTAB_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path


def test_the_readme_has_its_two_blocks():
    b = blocks()
    assert len(b) == 2, [x[:40] for x in b]
    assert "brdftab.open(" in b[0] and "mitsuba" in b[1]


def test_first_session_runs_as_written(repo_root):
    scope = {}
    exec(compile(blocks()[0], str(README), "exec"), scope)  # noqa: S102
    # what the block's comments say it gets
    assert scope["f"].shape == (2, 3) and scope["f"].dtype == np.float32
    assert scope["a"].shape == (3, 3)
    assert scope["grid"].shape == (2, 2, 3)
    assert (repo_root / "paper.btdb").is_file() and (repo_root / "paper-dim.btdb").is_file()
    assert sorted(scope["db"]) == ["shiny"]
    assert scope["wi_s"].shape == (2, 3) and np.all(scope["weight"] >= 0)


def test_mitsuba_block_runs_as_written(repo_root):
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        unavailable("mitsuba is not installed")
    if not os.environ.get("DRJIT_LIBLLVM_PATH"):
        unavailable("DRJIT_LIBLLVM_PATH is not set (the block's llvm variant needs it)")
    scope = {}
    exec(compile(blocks()[1], str(README), "exec"), scope)  # noqa: S102
    scope["mi"].Thread.wait_for_tasks()  # write_bitmap writes asynchronously
    img = np.asarray(scope["mi"].Bitmap(str(repo_root / "sphere.png"))).astype(int)
    assert img.shape == (256, 256, 3)
    # a corner sees the grey environment; the sphere's centre the golden yellow material
    r, g, b = img[2, 2]
    assert r == g == b and r > 0
    r, g, b = img[128, 128]
    assert r > b and g > b, img[128, 128]


def test_the_repository_readme_python_block_runs_as_written(repo_root, capsys):
    (block,) = blocks(ROOT / "README.md")
    exec(compile(block, str(ROOT / "README.md"), "exec"), {})  # noqa: S102
    printed = capsys.readouterr().out
    values = printed.strip().strip("[]").split()  # numpy's print of a (3,) array
    assert len(values) == 3 and all(float(v) > 0 for v in values), printed
