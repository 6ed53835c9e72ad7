"""numpydoc docstrings on the public API (``stabctl.__all__``), checked the way
python-control checks its own (control/tests/docstrings_test.py): every public function,
method (classmethods and staticmethods included) and constructor has a docstring that
documents each of its parameters in a ``Parameters`` section; a function that returns
something (by its annotation, or a ``return <value>`` of its own when unannotated) has a
``Returns`` section; one that raises an exception of its own (a ``raise`` in its body, or
in ``__post_init__`` / ``__init__`` for a class) has a ``Raises`` section; and every name
a ``Raises`` section lists is an exception class of stabctl.errors or builtins."""

from __future__ import annotations

import ast
import builtins
import dataclasses
import inspect
import re
import textwrap

import pytest

import stabctl
import stabctl.errors

SECTION = re.compile(
    r"^[ \t]*(Parameters|Other Parameters|Returns|Yields|Receives|Raises|"
    r"Warns|Warnings|Attributes|Methods|Notes|See Also|References|"
    r"Examples)[ \t]*\n[ \t]*-{3,}[ \t]*$",
    re.M,
)


def sections(doc: str) -> dict[str, str]:
    """numpydoc section name -> its body."""
    doc = inspect.cleandoc(doc)
    marks = list(SECTION.finditer(doc))
    return {
        m[1]: doc[m.end() : (marks[i + 1].start() if i + 1 < len(marks) else len(doc))]
        for i, m in enumerate(marks)
    }


def documented_names(body: str) -> set[str]:
    """Names in a Parameters/Attributes section: ``name : type`` or ``a, b : type``."""
    names = set()
    for line in body.splitlines():
        m = re.match(r"^([A-Za-z_*][\w*]*(?:\s*,\s*[A-Za-z_*][\w*]*)*)\s*(?::|$)", line)
        if m and not line.startswith(" "):
            names |= {n.strip().lstrip("*") for n in m[1].split(",")}
    return names


def exception_names(body: str) -> list[str]:
    """Names in a Raises section: each unindented line is ``Name`` or ``Name, Name``
    (optionally dotted, ``stabctl.errors.CaseError``); the indented lines describe them."""
    names = []
    for line in body.splitlines():
        if line.strip() and not line[0].isspace():
            names += [n.strip() for n in line.split(",") if n.strip()]
    return names


def is_exception_class(name: str) -> bool:
    """``name`` (last dotted part) is an exception class of stabctl.errors or builtins."""
    last = name.rsplit(".", 1)[-1]
    obj = getattr(stabctl.errors, last, None) or getattr(builtins, last, None)
    return inspect.isclass(obj) and issubclass(obj, BaseException)


def own_nodes(func):
    """AST nodes of ``func``'s own body (nested functions, lambdas and classes left out);
    empty when the source is not available."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return []
    nodes, todo = [], list(ast.iter_child_nodes(tree.body[0]))
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            continue
        nodes.append(node)
        todo.extend(ast.iter_child_nodes(node))
    return nodes


def returns_value(func) -> bool:
    """``func`` has a ``return <value>`` (other than ``return None``) of its own."""
    return any(
        isinstance(n, ast.Return)
        and n.value is not None
        and not (isinstance(n.value, ast.Constant) and n.value.value is None)
        for n in own_nodes(func)
    )


def raises_directly(func) -> bool:
    """``func`` has a ``raise <exception>`` of its own (a bare re-raise does not count)."""
    return any(isinstance(n, ast.Raise) and n.exc is not None for n in own_nodes(func))


def public_callables():
    """(label, callable, docstring owner) for every public function and class in __all__;
    for classes the constructor's parameters are checked against the class docstring
    (Parameters, or Attributes for dataclasses) and each public method in the class."""
    for name in stabctl.__all__:
        obj = getattr(stabctl, name)
        if inspect.isclass(obj):
            yield name, obj, obj
            for meth_name, meth in vars(obj).items():
                if isinstance(meth, (classmethod, staticmethod)):
                    meth = meth.__func__
                if not meth_name.startswith("_") and inspect.isfunction(meth):
                    yield f"{name}.{meth_name}", meth, meth
        elif callable(obj):
            yield name, obj, obj


CALLABLES = list(public_callables())


@pytest.mark.parametrize("label,obj,owner", CALLABLES, ids=[c[0] for c in CALLABLES])
def test_public_api_has_numpydoc_docstring(label, obj, owner):
    doc = owner.__doc__
    assert doc and doc.strip(), f"{label}: no docstring"
    secs = sections(doc)
    if inspect.isclass(obj):
        if dataclasses.is_dataclass(obj):
            params = [f.name for f in dataclasses.fields(obj) if f.init]
        else:
            params = list(inspect.signature(obj.__init__).parameters)[1:]
        body = secs.get("Parameters", "") + secs.get("Attributes", "")
    else:
        params = list(inspect.signature(obj).parameters)
        if params and params[0] in ("self", "cls"):
            params = params[1:]
        body = secs.get("Parameters", "") + secs.get("Other Parameters", "")
    sig = inspect.signature(obj.__init__ if inspect.isclass(obj) else obj)
    params = [
        p
        for p in params
        if sig.parameters.get(p) is None
        or sig.parameters[p].kind
        not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
    ]
    missing = set(params) - documented_names(body)
    assert not missing, f"{label}: parameters not documented: {sorted(missing)}"
    if not inspect.isclass(obj):
        ret = sig.return_annotation
        if ret is inspect.Signature.empty and returns_value(obj):
            ret = "a value"
        if (
            ret not in (inspect.Signature.empty, None, "None")
            and "Returns" not in secs
            and "Yields" not in secs
        ):
            pytest.fail(f"{label}: returns {ret} but has no Returns section")
    code = (
        obj.__post_init__
        if dataclasses.is_dataclass(obj) and hasattr(obj, "__post_init__")
        else obj.__init__
        if inspect.isclass(obj)
        else obj
    )
    if "Raises" not in secs and inspect.isfunction(code) and raises_directly(code):
        pytest.fail(f"{label}: raises but has no Raises section")
    for exc in exception_names(secs.get("Raises", "")):
        assert is_exception_class(exc), f"{label}: Raises names unknown {exc!r}"


def test_every_public_name_resolves():
    for name in stabctl.__all__:
        assert getattr(stabctl, name) is not None
