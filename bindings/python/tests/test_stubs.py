"""The installed package's typing and documentation: the stubs and the py.typed marker ship
beside the modules, every public name of the runtime has a docstring, and so has every public
name of the stubs. (That each stub's signature matches the runtime is mypy's `stubtest`, run by
.ci/run.)"""

import ast
import inspect
import pathlib
import re

import brdftab
import brdftab.mitsuba

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
