"""The stub grainscale/_core.pyi against the built extension.

stubtest (make lint) checks that every name exists on both sides, but pybind11 functions carry
no inspectable signature, so it cannot see parameter names or defaults. pybind11 writes the
signature into each docstring; these tests compare those with the stub.
"""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import pytest

import grainscale
from grainscale import _core

STUB = Path(grainscale.__file__).with_name("_core.pyi")


def _stub_classes() -> tuple[dict[str, ast.FunctionDef], dict[str, ast.ClassDef]]:
    tree = ast.parse(STUB.read_text())
    functions = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
    return functions, classes


def _split_top(text: str) -> list[str]:
    """Split at commas outside brackets and quotes."""
    parts, depth, quote, start = [], 0, "", 0
    for k, ch in enumerate(text):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:k].strip())
            start = k + 1
    if text[start:].strip():
        parts.append(text[start:].strip())
    return parts


def _runtime_params(obj: object, name: str) -> list[tuple[str, str | None]]:
    """(name, default source or None) from pybind11's docstring signature, without self."""
    doc = (getattr(obj, "__doc__", None) or "").strip().splitlines()[0]
    assert doc.startswith(name + "("), doc
    inner = doc[len(name) + 1 : doc.rindex(") ->")]
    params = []
    for part in _split_top(inner):
        head, _, default = part.partition(" = ")
        pname = head.split(":")[0].strip()
        if pname == "self":
            continue
        params.append((pname, default.strip() or None))
    return params


def _stub_params(fn: ast.FunctionDef) -> list[tuple[str, str | None]]:
    args = fn.args.posonlyargs + fn.args.args
    defaults: list[ast.expr | None] = [None] * (len(args) - len(fn.args.defaults))
    defaults += fn.args.defaults
    out = []
    for arg, default in zip(args, defaults, strict=True):
        if arg.arg != "self":
            out.append((arg.arg, None if default is None else ast.unparse(default)))
    if fn.args.vararg is not None:
        out.append(("*" + fn.args.vararg.arg, None))
    return out


def _same(runtime: list[tuple[str, str | None]], stub: list[tuple[str, str | None]]) -> None:
    assert [n for n, _ in runtime] == [n for n, _ in stub]
    for (name, rd), (_, sd) in zip(runtime, stub, strict=True):
        if rd is None or sd is None:
            assert rd == sd, name
        else:
            assert ast.literal_eval(rd) == ast.literal_eval(sd), name


def _runtime_classes() -> dict[str, type]:
    return {n: c for n, c in vars(_core).items() if inspect.isclass(c)}


def test_module_functions_match():
    functions, _ = _stub_classes()
    runtime = {n: f for n, f in vars(_core).items() if callable(f) and not inspect.isclass(f)}
    runtime = {n: f for n, f in runtime.items() if not n.startswith("_")}
    assert sorted(runtime) == sorted(functions)
    for name, fn in runtime.items():
        _same(_runtime_params(fn, name), _stub_params(functions[name]))


@pytest.mark.parametrize("cls_name", sorted(_runtime_classes()))
def test_class_members_match(cls_name):
    _, classes = _stub_classes()
    cls = _runtime_classes()[cls_name]
    body = classes[cls_name].body
    methods = {n.name: n for n in body if isinstance(n, ast.FunctionDef)}
    attributes = {
        n.target.id for n in body if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)
    }
    for name, member in vars(cls).items():
        if name.startswith("_") and name not in ("__init__", "__enter__", "__exit__"):
            continue
        if isinstance(member, property):
            if member.fset is None:
                decorators = [ast.unparse(d) for d in methods[name].decorator_list]
                assert decorators == ["property"], name
            else:
                assert name in attributes, f"{cls_name}.{name} is settable"
            continue
        if name == "__init__" and not (member.__doc__ or "").startswith("__init__("):
            assert name not in methods  # no constructor bound (stubtest allowlist)
            continue
        func = member.__func__ if isinstance(member, staticmethod) else member
        _same(_runtime_params(func, name), _stub_params(methods[name]))
