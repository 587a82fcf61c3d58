"""The type stubs describe the extension as built, and every public item has
a docstring."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import sdrs
import sdrs._sdrs as ext

STUB = Path(sdrs.__file__).with_name("_sdrs.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    out = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members = set()
            for b in node.body:
                if isinstance(b, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    members.add(b.name)
                elif isinstance(b, ast.AnnAssign) and isinstance(b.target, ast.Name):
                    members.add(b.target.id)
            out[node.name] = members
        elif isinstance(node, ast.FunctionDef):
            out[node.name] = None
    return out


def public(obj):
    return {n for n in dir(obj) if not n.startswith("_")}


def test_stubs_match_the_extension():
    stubs = stub_names()
    assert set(stubs) == public(ext) - {"sdrs"} or set(stubs) == public(ext)
    for name, members in stubs.items():
        obj = getattr(ext, name)
        if members is None:
            assert callable(obj)
        elif name != "SdrsError":
            assert members - {"__len__"} == public(obj), name


def test_every_public_item_has_a_docstring():
    for name in public(ext):
        obj = getattr(ext, name)
        assert inspect.getdoc(obj), name
        if inspect.isclass(obj) and not issubclass(obj, Exception):
            for m in public(obj):
                assert inspect.getdoc(getattr(obj, m)), f"{name}.{m}"
    import sdrs.ray
    import sdrs.torch

    for mod in (sdrs, sdrs.torch, sdrs.ray):
        assert mod.__doc__
        for n in mod.__all__:
            assert inspect.getdoc(getattr(mod, n)), f"{mod.__name__}.{n}"
