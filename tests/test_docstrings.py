"""numpydoc docstrings on the public API (``stabctl.__all__``), checked the way
python-control checks its own (control/tests/docstrings_test.py): every public function,
method and constructor documents each of its parameters in a ``Parameters`` section, a
function that returns something has a ``Returns`` section, and a documented ``Raises``
names exception classes that exist."""

from __future__ import annotations

import dataclasses
import inspect
import re

import pytest

import stabctl
import stabctl.errors

SECTION = re.compile(r"^\s*(Parameters|Returns|Raises|Attributes|Yields|Notes|See Also|"
                     r"References|Examples)\n\s*-{3,}\s*$", re.M)


def sections(doc: str) -> dict[str, str]:
    """numpydoc section name -> its body."""
    doc = inspect.cleandoc(doc)
    marks = list(SECTION.finditer(doc))
    return {m[1]: doc[m.end():(marks[i + 1].start() if i + 1 < len(marks) else len(doc))]
            for i, m in enumerate(marks)}


def documented_names(body: str) -> set[str]:
    """Names in a Parameters/Attributes section: ``name : type`` or ``a, b : type``."""
    names = set()
    for line in body.splitlines():
        m = re.match(r"^([A-Za-z_*][\w*]*(?:\s*,\s*[A-Za-z_*][\w*]*)*)\s*(?::|$)", line)
        if m and not line.startswith(" "):
            names |= {n.strip().lstrip("*") for n in m[1].split(",")}
    return names


def public_callables():
    """(label, callable, docstring owner) for every public function and class in __all__;
    for classes the constructor's parameters are checked against the class docstring
    (Parameters, or Attributes for dataclasses) and each public method in the class."""
    for name in stabctl.__all__:
        obj = getattr(stabctl, name)
        if inspect.isclass(obj):
            yield name, obj, obj
            for meth_name, meth in vars(obj).items():
                if (not meth_name.startswith("_") and inspect.isfunction(meth)
                        and meth.__doc__ is not None):
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
        body = secs.get("Parameters", "")
    sig = inspect.signature(obj.__init__ if inspect.isclass(obj) else obj)
    params = [p for p in params
              if sig.parameters.get(p) is None
              or sig.parameters[p].kind not in (inspect.Parameter.VAR_POSITIONAL,
                                                inspect.Parameter.VAR_KEYWORD)]
    missing = set(params) - documented_names(body)
    assert not missing, f"{label}: parameters not documented: {sorted(missing)}"
    if not inspect.isclass(obj):
        ret = sig.return_annotation
        if ret not in (inspect.Signature.empty, None, "None") and "Returns" not in secs \
                and "Yields" not in secs:
            pytest.fail(f"{label}: returns {ret} but has no Returns section")
    for exc in re.findall(r"^([A-Z]\w+(?:Error|Exception|Warning))", secs.get("Raises", ""),
                          re.M):
        assert hasattr(stabctl.errors, exc) or hasattr(__builtins__, exc) or \
            exc in dir(__import__("builtins")), f"{label}: Raises names unknown {exc}"


def test_every_public_name_resolves():
    for name in stabctl.__all__:
        assert getattr(stabctl, name) is not None
