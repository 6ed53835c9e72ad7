"""The compiled dispatch on the model type, generated from a family's registry.

numba compiles a call only to a function it knows when it types the caller, so a family's
kernels (`stabctl.models.governors.pmech`, ...) reach their type modules' kernels through
an ``if kind == ...`` chain written out in source; and the kernels are cached on disk per
source file (`stabctl._jit.decorators.kernel`), so that source must be a real file.  This
module writes it: for each family in :data:`FAMILIES`, a committed module ``_dispatch.py``
in the family's package with one kernel per entry of its :class:`Dispatch`, each branching
on the packed type column to the same-named kernel of every module of the registry
(``MODULES``), all of them called with the same arguments.  Adding a type is its module and
its line in ``MODULES``, then::

    python -m stabctl.models.dispatch

which rewrites every family's ``_dispatch.py``; tests/models/test_dispatch.py fails, naming
this command, when a committed file differs from what it would write.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import inspect
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Kernel", "Dispatch", "FAMILIES", "render", "target", "main"]

#: the command that writes the files, named in their header and in the test's message
COMMAND = "python -m stabctl.models.dispatch"


@dataclass(frozen=True)
class Kernel:  # fields of a dataclass: numpydoc ignore=PR02
    """One dispatched kernel: each type module's function `name`, called with `args`.

    Parameters
    ----------
    name : str
        The kernel's name, the family's and every type module's.
    args : tuple of str
        Its arguments, the same for every type (the packed parameters first, then the
        type's row ``k`` among them).
    doc : str
        The family kernel's docstring.
    returns : bool
        The type's kernel returns the value (the family's returns it); else it writes its
        results into its arguments.
    first : str
        A statement run before the dispatch (empty: none).
    inline : bool
        Compiled into its caller (``@kernel(inline="always")``), for a dispatch the
        family's own kernel wraps.
    generated : str
        The generated kernel's name (empty: `name`).
    default : str
        For a kernel a type module may leave out: the expression the generated kernel
        returns for its types (empty: every module has the kernel).
    kind : bool
        The first of `args`, ``kind``, is the type itself, not passed on to the type's kernel (a
        function Python code calls too, ``@njit``); else the type is the packed type
        column of the row ``args[2]``.
    """

    name: str
    args: tuple[str, ...]
    doc: str
    returns: bool
    first: str = ""
    inline: bool = False
    generated: str = ""
    default: str = ""
    kind: bool = False

    @property
    def passed(self) -> tuple[str, ...]:
        """The arguments the type's kernel takes: `args`, without the type with `kind`."""
        return self.args[1:] if self.kind else self.args


@dataclass(frozen=True)
class Dispatch:  # fields of a dataclass: numpydoc ignore=PR02
    """A family's dispatched kernels.

    Parameters
    ----------
    package : str
        The family's package, whose ``MODULES`` is its registry (each module with
        ``KINDS``, type code -> name).
    what : str
        What the type is, for the module docstring ("governor type").
    layout : str
        The module and name of the packed columns (``"table.G"``), whose ``KIND`` is the
        type's column.
    kernels : tuple of Kernel
        The kernels.
    """

    package: str
    what: str
    layout: str
    kernels: tuple[Kernel, ...]


FAMILIES = (
    Dispatch(
        "stabctl.models.governors",
        "governor type (tg_con column 1)",
        "table.G",
        (
            Kernel(
                "pmech",
                ("P", "x", "k", "omega"),
                "Mechanical power of governor k (machine base) at machine speed omega "
                "(pu), flag 1: its type module's ``pmech``.",
                returns=True,
            ),
            Kernel(
                "derivatives",
                ("P", "x", "k", "omega", "pe", "dx"),
                "Derivatives of governor k into dx[:, k] for its machine speed omega (pu) "
                "and electrical power pe (pu on the machine base), flag 2: its type "
                "module's ``derivatives`` (which clamp the limited states in x).",
                returns=False,
                first="zero_column(dx, k)",
            ),
        ),
    ),
    Dispatch(
        "stabctl.models.pss",
        "stabiliser type (pss_con column 1)",
        "table.C",
        (
            Kernel(
                "output",
                ("P", "x", "k", "omega", "pe", "dx"),
                "Output of PSS k (pu, before the output cut-off) at machine speed omega (pu) "
                "and electrical power pe (machine base); its derivatives into dx[:, k]: its "
                "type module's ``output``.",
                returns=True,
                inline=True,
            ),
        ),
    ),
    Dispatch(
        "stabctl.models.exciters",
        "exciter type (exc_con column 1)",
        "table.E",
        (
            Kernel(
                "field_voltage",
                ("P", "x", "i", "VTR_alg", "pss_out", "VB", "ifd", "ieee"),
                "Field voltage of exciter i given its machine's terminal voltage VTR_alg "
                "(pu), its PSS's output pss_out, the source term VB (`source_voltage`), the "
                "field current ifd (`field_current`) and the IEEE 421.5 convention ieee: "
                "its type module's ``field_voltage``.",
                returns=True,
                inline=True,
                generated="field_voltage_at",
            ),
            Kernel(
                "derivatives",
                (
                    "P",
                    "x",
                    "i",
                    "err",
                    "eterm",
                    "efd",
                    "ifd",
                    "pss_out",
                    "VB",
                    "dx",
                    "ieee",
                    "reach",
                ),
                "Derivatives of exciter i past its transducer (`derivatives`) into dx[:, i] "
                "for its voltage error err: its type module's ``derivatives``.",
                returns=False,
                inline=True,
                generated="type_derivatives",
            ),
            Kernel(
                "recorded_efd",
                ("P", "x", "i", "efd_alg"),
                "Efd as PST records exciter i's: its type module's ``recorded_efd`` where it "
                "has one, else the algebraic field voltage efd_alg.",
                returns=True,
                inline=True,
                generated="type_recorded_efd",
                default="efd_alg",
            ),
            Kernel(
                "source_voltage",
                ("kind", "KP", "KI", "XL", "KC", "cap", "machine", "init"),
                "The source term V_B of an exciter of type kind from its machine's "
                "quantities machine (`table.ST3Machine`), its K_P (complex), K_I, X_L, K_C, "
                "its cap VBmax and init (PST's flag 0): its type module's "
                "``source_voltage`` (the types that declare ``SOURCE``), 1 for the others.",
                returns=True,
                generated="source_voltage_of",
                default="1.0",
                kind=True,
            ),
        ),
    ),
)


def _wrapped(text: str, indent: str, width: int = 92) -> list[str]:
    """`text` as lines of at most `width` characters after `indent`."""
    lines, line = [], ""
    for word in text.split():
        if line and len(line) + 1 + len(word) > width - len(indent):
            lines.append(indent + line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    return [*lines, indent + line]


def _check(module, kernel: Kernel) -> None:
    """Raise ValueError unless `module` has the kernel with the kernel's arguments."""
    fn = getattr(module, kernel.name, None)
    if fn is None:
        raise ValueError(f"{module.__name__} has no kernel '{kernel.name}'")
    params = tuple(inspect.signature(getattr(fn, "py_func", fn)).parameters)
    if params != kernel.passed:
        raise ValueError(
            f"{module.__name__}.{kernel.name}{params}: the family's kernels take "
            f"({', '.join(kernel.passed)})"
        )


def render(family: Dispatch) -> str:
    """The source of `family`'s ``_dispatch.py`` from its package's ``MODULES``.

    Parameters
    ----------
    family : Dispatch
        The family.

    Returns
    -------
    str
        The module's source.

    Raises
    ------
    ValueError
        A type module without one of the kernels, or with other arguments.
    """
    modules = [m for m in importlib.import_module(family.package).MODULES if m.KINDS]
    for module in modules:
        for kernel in family.kernels:
            if not kernel.default or hasattr(module, kernel.name):
                _check(module, kernel)
    layout_module, layout = family.layout.rsplit(".", 1)
    names = ", ".join(f"`{k.generated or k.name}`" for k in family.kernels)
    header = (
        f'"""The dispatch on the {family.what} of the compiled kernels {names}: generated '
        f"by ``{COMMAND}`` from the registry ({family.package}.MODULES), do not edit."
        '"""'
    )
    branches = {k.name: _branches(modules, k) for k in family.kernels}
    used = sorted({s for kernel in branches.values() for s, _, _ in kernel})
    decorators = "kernel, njit" if any(k.kind for k in family.kernels) else "kernel"
    arrays = (
        ["from stabctl._jit.arrays import zero_column"]
        if any("zero_column(" in k.first for k in family.kernels)
        else []
    )
    out = [
        *_wrapped(header, ""),
        "",
        "from __future__ import annotations",
        "",
        *arrays,
        f"from stabctl._jit.decorators import {decorators}",
        f"from {family.package} import (",
        *(f"    {s}," for s in used),
        ")",
        f"from {family.package}.{layout_module} import {layout}",
    ]
    for kernel in family.kernels:
        args = ", ".join(kernel.args)
        decorator = '@kernel(inline="always")' if kernel.inline else "@kernel"
        out += ["", "", "@njit" if kernel.kind else decorator]
        out.append(f"def {kernel.generated or kernel.name}({args}):")
        out += _wrapped(f'"""{kernel.doc}"""', "    ")
        if not kernel.kind:
            out.append(f"    kind = P[{kernel.args[2]}, {layout}.KIND]")
        if kernel.first:
            out.append(f"    {kernel.first}")
        chain = branches[kernel.name]
        for i, (s, kinds, label) in enumerate(chain):
            call = f"{s}.{kernel.name}({', '.join(kernel.passed)})"
            test = " or ".join(f"kind == {kind}" for kind in kinds)
            last = i == len(chain) - 1 and not kernel.default
            if kernel.returns:
                if not last:
                    out.append(_noted(f"    if {test}:", label))
                    out.append(f"        return {call}")
                else:
                    out.append(_noted(f"    return {call}", label))
            else:
                keyword = "if" if i == 0 else "elif"
                if not last:
                    out.append(_noted(f"    {keyword} {test}:", label))
                else:
                    out.append(_noted("    else:", label))
                out.append(f"        {call}")
        if kernel.default:
            out.append(f"    return {kernel.default}  # the other types")
    return "\n".join(out) + "\n"


def _noted(line: str, label: str) -> str:
    """`line` with the comment `label`, or without it where it would pass 100 characters."""
    noted = f"{line}  # {label}"
    return noted if len(noted) <= 100 else line


def _branches(modules, kernel: Kernel) -> list[tuple[str, list[int], str]]:
    """The dispatch chain of `kernel`: (module, its types, their names) per branch, in
    registry order; the modules whose kernel is one function (PSS2B runs PSS2A's) share
    the first one's branch."""
    chain: list[tuple[str, list[int], str]] = []
    seen: dict[int, int] = {}
    for module in modules:
        fn = getattr(module, kernel.name, None)
        if fn is None:  # a kernel with a default
            continue
        if id(fn) in seen:
            s, kinds, label = chain[seen[id(fn)]]
            chain[seen[id(fn)]] = (
                s,
                [*kinds, *module.KINDS],
                label + "; " + "; ".join(module.KINDS.values()),
            )
            continue
        seen[id(fn)] = len(chain)
        short = module.__name__.rsplit(".", 1)[1]
        chain.append((short, list(module.KINDS), "; ".join(module.KINDS.values())))
    return chain


def target(family: Dispatch) -> Path:
    """The file of `family`'s dispatch: ``_dispatch.py`` in its package (found without
    importing the package, which imports it)."""
    spec = importlib.util.find_spec(family.package)
    assert spec is not None and spec.origin is not None, family.package
    return Path(spec.origin).parent / "_dispatch.py"


def _placeholder(family: Dispatch) -> str:
    """A ``_dispatch.py`` that imports no type module: written in place of one that names
    a module the registry no longer has (whose import fails), so that the package
    imports and its dispatch can be generated; `_generated` overwrites it at once, and a
    kernel called meanwhile raises naming the command."""
    lines = [f'"""Placeholder: run ``{COMMAND}``."""']
    for kernel in family.kernels:
        name = kernel.generated or kernel.name
        lines += [
            "",
            "",
            f"def {name}(*args):",
            f'    raise RuntimeError("{family.package}._dispatch is being written: run {COMMAND}")',
        ]
    return "\n".join(lines) + "\n"


def _generated(family: Dispatch) -> str:
    """`render`, after replacing a ``_dispatch.py`` whose import fails (a type module
    removed from the registry and its package) with `_placeholder`."""
    try:
        return render(family)
    except ImportError:
        target(family).write_text(_placeholder(family), "utf-8")
        for name in [n for n in sys.modules if n.startswith(family.package)]:
            del sys.modules[name]
        return render(family)


def main(argv=None) -> int:
    """Write every family's ``_dispatch.py`` (:data:`FAMILIES`); with ``--check``, only
    report the ones that differ (exit status 1).

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0, or 1 when ``--check`` found a file to rewrite.
    """
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="only report stale files")
    a = ap.parse_args(argv)
    stale = 0
    for family in FAMILIES:
        path = target(family)
        text = render(family) if a.check else _generated(family)
        if path.exists() and path.read_text("utf-8") == text:
            continue
        stale += 1
        if a.check:
            print(f"{path} is stale: run {COMMAND}")
        else:
            path.write_text(text, "utf-8")
            print(f"wrote {path}")
    return 1 if a.check and stale else 0


if __name__ == "__main__":
    raise SystemExit(main())
