"""The kernel coding rules of `stabctl._jit` (its docstring), checked on the package's
source: each test scans the kernels (functions decorated with `kernel` or `njit`) or the
Python code around them and names every offending line."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import numpy as np
import pytest
from numba.core.dispatcher import Dispatcher

from stabctl._jit.cache import _DECORATOR, declaring_modules
from stabctl._jit.decorators import CompiledOnly

PKG = Path(__file__).resolve().parents[1] / "stabctl"


def _parsed(module):
    return ast.parse(Path(module.__file__).read_text("utf-8"))


def _declaring():
    """(module, its AST) of every package module that declares a kernel."""
    return [(mod, _parsed(mod)) for mod in map(importlib.import_module, declaring_modules())]


DECLARING = _declaring()


def _decorated(fn: ast.FunctionDef) -> bool:
    return any(_DECORATOR.match("@" + ast.unparse(d)) for d in fn.decorator_list)


def _kernel_bodies():
    """(module, function AST) of every kernel (numba dispatchers; not the typing code of
    an ``intrinsic``)."""
    return [
        (mod, node)
        for mod, tree in DECLARING
        for node in tree.body
        if isinstance(node, ast.FunctionDef)
        and _decorated(node)
        and isinstance(getattr(mod, node.name), Dispatcher)
    ]


def _resolve(mod, expr):
    """The object an expression ``name`` or ``module.name`` stands for in `mod`, or None."""
    if isinstance(expr, ast.Name):
        return getattr(mod, expr.id, None)
    if isinstance(expr, ast.Attribute):
        owner = _resolve(mod, expr.value)
        return getattr(owner, expr.attr, None) if owner is not None else None
    return None


def _where(mod, node) -> str:
    return f"{mod.__name__}:{node.lineno}"


def test_the_scan_finds_the_kernels_of_every_layer():
    names = {mod.__name__ for mod, _ in DECLARING}
    assert {
        "stabctl._jit.arrays",
        "stabctl.dynamics.integrator",
        "stabctl.dynamics.model",
        "stabctl.dynamics.switching",
        "stabctl.models.machines",
        "stabctl.network.solution",
        "stabctl.smallsignal.linearise",
    } <= names
    assert len(_kernel_bodies()) > 50


def _bare_numba(tree) -> list[int]:
    """Lines of a module that use numba's own ``njit``/``jit`` decorator."""
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == "numba":
            lines += [node.lineno for a in node.names if a.name in ("njit", "jit")]
        if isinstance(node, ast.Attribute) and ast.unparse(node) in ("numba.njit", "numba.jit"):
            lines.append(node.lineno)
    return lines


def test_every_kernel_is_declared_by_the_jit_decorators():
    # rule 1: cached (numba's FunctionCache, guarded against damaged entries:
    # stabctl._jit.cache.GuardedCache), and never a bare numba.njit / numba.jit
    bad = [
        _where(mod, fn)
        for mod, fn in _kernel_bodies()
        if type(getattr(mod, fn.name)._cache).__name__ != "GuardedCache"
    ]
    bad += [
        f"{f.relative_to(PKG)}:{line}"
        for f in PKG.rglob("*.py")
        if f.parent.name != "_jit"
        for line in _bare_numba(ast.parse(f.read_text("utf-8")))
    ]
    assert not bad, bad


def _python_functions(tree):
    """The functions of a module that run in Python: not kernels, and not in a filterpy
    reference implementation (a class named ``*Reference``, which calls the kernels of the
    filters it checks through their trampolines)."""
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and not _decorated(node):
            yield node
        elif isinstance(node, ast.ClassDef) and not node.name.endswith("Reference"):
            yield from (n for n in node.body if isinstance(n, ast.FunctionDef))


def _python_calls_of_kernels(mod, tree) -> list[str]:
    return [
        _where(mod, call)
        for fn in _python_functions(tree)
        for call in ast.walk(fn)
        if isinstance(call, ast.Call) and isinstance(_resolve(mod, call.func), CompiledOnly)
    ]


def test_package_code_never_calls_a_compiled_only_kernel_from_python():
    # rule 2: a `kernel` has no CPython entry point; only tests use its trampoline
    bad = []
    for source in PKG.rglob("*.py"):
        if source.name != "__main__.py":
            name = ".".join(("stabctl", *source.relative_to(PKG).with_suffix("").parts))
            mod = importlib.import_module(name.removesuffix(".__init__"))
            bad += _python_calls_of_kernels(mod, _parsed(mod))
    assert not bad, bad


def test_the_python_and_decorator_scans_find_offenders():
    # rules 1 and 2 on a made-up module: numba's own decorator, a kernel called from Python
    import types

    from stabctl._jit.arrays import max_abs

    mod = types.ModuleType("stabctl.offending_for_the_test")
    mod.max_abs = max_abs
    tree = ast.parse(
        "import numba\n@numba.njit\ndef g(a):\n    return a\n"
        "class A:\n    def f(self, a):\n        return max_abs(a)\n"
    )
    assert _bare_numba(tree) == [2]
    assert _python_calls_of_kernels(mod, tree) == ["stabctl.offending_for_the_test:7"]


def _is_scalar(expr) -> bool:
    return isinstance(expr, ast.Constant) or (
        isinstance(expr, ast.UnaryOp) and isinstance(expr.operand, ast.Constant)
    )


def test_no_kernel_assigns_an_array_into_a_slice():
    # rule 3: `assign` instead of a[:] = b (numba compiles a shape-message formatter)
    bad = []
    for mod, fn in _kernel_bodies():
        for node in ast.walk(fn):
            if not isinstance(node, (ast.Assign, ast.AugAssign)) or _is_scalar(node.value):
                continue
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                index = t.slice if isinstance(t, ast.Subscript) else None
                parts = index.elts if isinstance(index, ast.Tuple) else [index]
                if any(
                    isinstance(p, ast.Slice)
                    or (isinstance(p, ast.Constant) and p.value is Ellipsis)
                    for p in parts
                ):
                    bad.append(f"{_where(mod, node)}: {ast.unparse(node)}")
    assert not bad, bad


def test_kernels_pass_numpy_scalars_not_python_literals_to_kernels():
    # rule 4: a Python bool/int argument (a literal or a module constant) is typed as a
    # literal, and the callee compiles once per value: no argument of a kernel may get
    # such a constant at one call and another value (another constant, or a variable) at
    # another
    seen: dict[tuple, dict] = {}
    for mod, fn in _kernel_bodies():
        for call in ast.walk(fn):
            callee = _resolve(mod, call.func) if isinstance(call, ast.Call) else None
            if not isinstance(callee, Dispatcher):
                continue
            for pos, arg in enumerate(call.args):
                value = arg.value if isinstance(arg, ast.Constant) else _resolve(mod, arg)
                kind = repr(value) if type(value) in (bool, int) else "a variable"
                seen.setdefault((callee.py_func.__qualname__, pos), {}).setdefault(
                    kind, _where(mod, call)
                )
    bad = {
        (name, pos): kinds
        for (name, pos), kinds in seen.items()
        if len(kinds) > 1 and set(kinds) != {"a variable"}
    }
    assert not set(bad) - KNOWN_LITERALS, bad


#: known breaches of rule 4 (none: the blocks' forms and slots are numpy scalars)
KNOWN_LITERALS: set = set()


def _numpy_calls(fn, names):
    return [
        c
        for c in ast.walk(fn)
        if isinstance(c, ast.Call)
        and ast.unparse(c.func) in {f"{np_}.{n}" for np_ in ("np", "numpy") for n in names}
    ]


def test_no_kernel_uses_numpys_linear_algebra():
    # rule 5: LAPACK by symbol (network.solution's dgesv), not np.linalg
    bad = [
        f"{_where(mod, node)}: {ast.unparse(node)}"
        for mod, fn in _kernel_bodies()
        for node in ast.walk(fn)
        if isinstance(node, ast.Attribute) and node.attr == "linalg"
    ]
    assert not bad, bad


def test_no_kernel_takes_the_largest_magnitude_with_numpys_reduction():
    # rule 6: np.max(np.abs(a)) is `max_abs`
    bad = [
        f"{_where(mod, c)}: {ast.unparse(c)}"
        for mod, fn in _kernel_bodies()
        for c in _numpy_calls(fn, ("max", "amax", "nanmax"))
        if c.args
        and isinstance(c.args[0], ast.Call)
        and ast.unparse(c.args[0].func) in ("np.abs", "numpy.abs", "abs")
    ]
    assert not bad, bad


@pytest.mark.parametrize(
    "rule, source",
    [
        (test_no_kernel_assigns_an_array_into_a_slice, "def f(a, b):\n    a[1:] = b\n"),
        (
            test_kernels_pass_numpy_scalars_not_python_literals_to_kernels,
            "def f(a):\n    g(a, True)\n    return g(a, False)\n",
        ),
        (test_no_kernel_uses_numpys_linear_algebra, "def f(a):\n    return np.linalg.inv(a)\n"),
        (
            test_no_kernel_takes_the_largest_magnitude_with_numpys_reduction,
            "def f(a):\n    return np.max(np.abs(a))\n",
        ),
    ],
)
def test_each_rule_fails_on_an_offending_kernel(rule, source, monkeypatch):
    # the scans above do find what they forbid: a kernel breaking the rule fails them
    import types

    import numba

    mod = types.ModuleType("stabctl.offending_for_the_test")
    mod.np, mod.g = np, numba.njit(lambda a, flag: a)
    fn = ast.parse("@kernel\n" + source).body[0]
    monkeypatch.setitem(globals(), "_kernel_bodies", lambda: [(mod, fn)])
    with pytest.raises(AssertionError):
        rule()
