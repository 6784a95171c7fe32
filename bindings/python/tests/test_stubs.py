"""The installed package's typing and documentation: the stubs and the py.typed marker ship
beside the modules, every public name of the runtime has a docstring, and so has every public
name of the stubs. (That each stub's signature matches the runtime is mypy's `stubtest`, run by
.ci/run.)"""

import ast
import inspect
import pathlib
import re
import subprocess
import sys

import brdftab
import brdftab.mitsuba
from conftest import unavailable

PKG = pathlib.Path(brdftab.__file__).parent
MODULES = [brdftab, brdftab.mitsuba]


def test_the_stubs_and_py_typed_ship_with_the_package():
    for name in ["py.typed", "__init__.pyi", "mitsuba.pyi"]:
        assert (PKG / name).is_file(), f"{name} is not installed beside {brdftab.__file__}"


def _public(names):
    return [n for n in names if not n.startswith("_")]


def _runtime_members():
    """(qualified name, object) of every public function, class, method and property the
    modules define (the plugin's classes with the methods `plugin_class` copies from their
    private base)."""
    for mod in MODULES:
        for n in _public(dir(mod)):
            obj = getattr(mod, n)
            if inspect.ismodule(obj) or not (inspect.isclass(obj) or callable(obj)):
                continue
            if getattr(obj, "__module__", None) not in (mod.__name__, "brdftab._native", "brdftab"):
                continue  # imported from elsewhere (numpy, math, ...)
            yield f"{mod.__name__}.{n}", obj
            if inspect.isclass(obj):
                for cls in obj.__mro__:
                    if cls.__module__ == "builtins":
                        continue  # object, Exception: Python's own
                    for k, v in vars(cls).items():
                        if not k.startswith("_"):
                            yield f"{mod.__name__}.{n}.{k}", v


def test_every_public_runtime_name_has_a_docstring():
    missing = []
    for qual, obj in _runtime_members():
        fn = obj.__func__ if isinstance(obj, (staticmethod, classmethod)) else obj
        doc = getattr(fn, "__doc__", None)
        if not (doc and doc.strip()):
            missing.append(qual)
    assert not missing, f"no docstring: {missing}"
    assert sum(1 for _ in _runtime_members()) > 40  # the walk saw the package


def _stub_defs(tree, prefix=""):
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            yield prefix + node.name, node
            if isinstance(node, ast.ClassDef):
                yield from _stub_defs(node, prefix + node.name + ".")


def test_every_public_stub_has_a_docstring():
    missing, seen = [], 0
    for stub in ["__init__.pyi", "mitsuba.pyi"]:
        tree = ast.parse((PKG / stub).read_text(encoding="utf-8"))
        for qual, node in _stub_defs(tree):
            if any(part.startswith("_") for part in qual.split(".")):
                continue  # private, and dunders (__init__, __repr__, ...)
            seen += 1
            if ast.get_docstring(node) is None:
                missing.append(f"{stub}: {qual}")
    assert not missing, f"stubs without a docstring: {missing}"
    assert seen > 40


def test_the_stubs_name_what_the_runtime_exports():
    tree = ast.parse((PKG / "__init__.pyi").read_text(encoding="utf-8"))
    stub_all = next(
        ast.literal_eval(n.value) for n in tree.body
        if isinstance(n, ast.Assign) and any(getattr(t, "id", None) == "__all__" for t in n.targets)
    )
    assert stub_all == brdftab.__all__


# Rustdoc's link syntax, which PyO3 copies from a Rust doc comment into the docstring that
# `help()` shows: [`Foo`], [`Foo`](crate::bar), [text](self::x), [Foo], [foo::bar].
RUSTDOC_LINK = re.compile(
    r"\[`[^`\n]+`\]|\]\((?:crate|self|super)::|\[(?:[A-Z]\w*|\w+(?:::\w+)+)\](?![\[(])"
)


def _rustdoc_links(doc):
    return [m.group(0) for m in RUSTDOC_LINK.finditer(doc or "")]


def test_docstrings_read_as_python_docs_not_rustdoc():
    """What `help(brdftab.X)` shows carries no rustdoc link syntax (the extension's docstrings
    are its Rust doc comments): `bake`, `convert`, `fit` and `bake_cached` showed
    [`BakeSettings`], [`request::convert`], [`FitSettings`] and [`brdftab::cache`]."""
    found = []
    for mod in [*MODULES, brdftab._native]:
        found += [(mod.__name__, x) for x in _rustdoc_links(mod.__doc__)]
        for n in dir(mod):
            obj = getattr(mod, n)
            if callable(obj) and getattr(obj, "__module__", None) in ("brdftab._native", "brdftab"):
                found += [(f"{mod.__name__}.{n}", x) for x in _rustdoc_links(obj.__doc__)]
    for qual, obj in _runtime_members():
        fn = obj.__func__ if isinstance(obj, (staticmethod, classmethod)) else obj
        found += [(qual, x) for x in _rustdoc_links(getattr(fn, "__doc__", None))]
    for stub in ["__init__.pyi", "mitsuba.pyi"]:
        tree = ast.parse((PKG / stub).read_text(encoding="utf-8"))
        found += [(stub, x) for x in _rustdoc_links(ast.get_docstring(tree))]
        found += [(f"{stub}: {q}", x) for q, node in _stub_defs(tree)
                  for x in _rustdoc_links(ast.get_docstring(node))]
    assert not found, f"rustdoc link syntax in docstrings: {sorted(set(found))}"
    assert _rustdoc_links("see [`Foo`](crate::bar), [a table](self::t), [Foo] and [a::b]") == [
        "[`Foo`]", "](self::", "[Foo]", "[a::b]"]
    assert _rustdoc_links('`grid["stored_shape"] + [c]`, ["R", "G", "B"], [0, 1)') == []


# A program that passes each call what its docstring and the README say it takes: bytes, str or
# pathlib.Path paths; any buffer to `Database.add_bytes` (its docstring names bytearray,
# memoryview and mmap). Type-checked, not run.
USES = """
import array, mmap, pathlib
import numpy as np
import brdftab

db = brdftab.Database(pathlib.Path("m.btdb"))
brdftab.Database(b"m.btdb").add('{"model": "lambert", "kd": 0.5}', "matte", preset="small")
with open("t.btdb", "rb") as fh:
    db.add_bytes("a", fh.read())
    db.add_bytes("b", bytearray(b"x"))
    db.add_bytes("c", memoryview(b"x"))
    db.add_bytes("d", mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ))
    db.add_bytes("e", array.array("B", b"x"))
b = brdftab.open(b"t.btdb", interp="linear")
f = b.eval(np.zeros((4, 3), np.float32), [0.0, 0.0, 1.0])
t = b.table()
t.save(pathlib.Path("u.btdb"), codec="f32")
brdftab.bake_cached("t.btdb", cache_dir=pathlib.Path("cache"), preset="small")
brdftab.info(pathlib.Path("t.btdb"))
"""


def test_the_stubs_accept_what_the_docstrings_say_each_call_takes(tmp_path):
    """mypy checks a program that passes the documented argument types against the installed
    stubs: the stub of `Database.add_bytes` took bytes | bytearray | memoryview, so mypy
    refused the mmap its docstring names (and any other buffer, an array.array)."""
    try:
        import mypy  # noqa: F401
    except ImportError:
        unavailable("no mypy (pip install mypy)")
    (tmp_path / "uses.py").write_text(USES, encoding="utf-8")
    # From the program's directory: mypy finds the installed package (py.typed), not a copy
    # under the working directory.
    r = subprocess.run([sys.executable, "-m", "mypy", "--no-incremental", "uses.py"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "Success" in r.stdout
