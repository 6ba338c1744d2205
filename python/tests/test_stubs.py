"""The type stubs (_lasercell.pyi) name every public class, function, method and property of the
compiled module, with the same parameter names as pybind11 reports."""

import ast
import inspect
import os
import re

import lasercell
from lasercell import _lasercell


def stub_tree():
    path = os.path.join(os.path.dirname(lasercell.__file__), "_lasercell.pyi")
    with open(path, encoding="utf-8") as f:
        return ast.parse(f.read())


def stub_params(function):
    args = function.args
    return [a.arg for a in args.posonlyargs + args.args if a.arg != "self"]


def runtime_params(obj):
    """Parameter names from pybind11's signature line, e.g. 'f(self, a: int, b: str = ...)'."""
    doc = (getattr(obj, "__doc__", None) or "").lstrip()
    match = re.match(r"\w+\((.*?)\) ->", doc.split("\n")[0])
    assert match, f"no signature in {obj!r}: {doc[:80]!r}"
    params, depth, current = [], 0, ""
    for char in match.group(1) + ",":  # split at the commas outside brackets
        depth += {"[": 1, "(": 1, "]": -1, ")": -1}.get(char, 0)
        if char == "," and depth == 0:
            params.append(current)
            current = ""
        else:
            current += char
    names = [p.split(":")[0].strip() for p in params if p.strip()]
    return [n for n in names if n != "self"]


def public(names):
    return {n for n in names if not n.startswith("_")}


def test_every_module_name_is_in_the_stub():
    tree = stub_tree()
    stubbed = {node.name for node in tree.body if isinstance(node, (ast.ClassDef, ast.FunctionDef))}
    runtime = public(dir(_lasercell)) - {"ArrayLike", "Joints"}
    assert stubbed == runtime


def test_functions_and_methods_have_the_runtime_parameters():
    for node in stub_tree().body:
        if isinstance(node, ast.FunctionDef):
            assert stub_params(node) == runtime_params(getattr(_lasercell, node.name)), node.name
        if not isinstance(node, ast.ClassDef):
            continue
        cls = getattr(_lasercell, node.name)
        if issubclass(cls, BaseException):
            continue
        members = {n.name: n for n in node.body if isinstance(n, ast.FunctionDef)}
        runtime_members = public(name for name, _ in inspect.getmembers(cls))
        assert public(members) == runtime_members, node.name
        for name, function in members.items():
            attr = inspect.getattr_static(cls, name)
            if isinstance(attr, property):
                continue
            target = getattr(cls, name)
            assert stub_params(function) == runtime_params(target), f"{node.name}.{name}"
