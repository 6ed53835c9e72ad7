"""Calling a kernel by its machine-code address, so that the caller's compiled unit does not
link it (rule 7 of `stabctl._jit`).

`address_of` compiles (or loads) the callee for fixed argument types and gives its address;
`by_address` makes the intrinsic that calls it from compiled code.  A call by address keeps
the callee out of the caller's unit: the two compile separately (in parallel processes,
`stabctl._jit.background`) and LLVM optimises and emits the callee once.
"""

from __future__ import annotations

import inspect

from numba import types
from numba.core.errors import TypingError
from numba.extending import intrinsic


def address_of(dispatcher, argtypes) -> int:
    """Machine-code address of a kernel compiled for given argument types (loaded from the
    cache or compiled here).

    Parameters
    ----------
    dispatcher : numba dispatcher
        The kernel; it must return an integer (intp), what `by_address` reads.
    argtypes : tuple of numba types
        Its argument types.

    Returns
    -------
    int
        The address; valid while this process lives (the dispatcher keeps the code).

    Raises
    ------
    RuntimeError
        The compiled code defines no such function, or it does not return an intp.
    """
    argtypes = tuple(argtypes)
    dispatcher.compile(argtypes)
    cres = dispatcher.overloads[argtypes]
    address = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
    if not address or cres.signature.return_type != types.intp:
        raise RuntimeError(
            f"{dispatcher.py_func.__qualname__}: no compiled function returning intp for {argtypes}"
        )
    return address


def by_address(name: str, names: tuple[str, ...], fixed):
    """An intrinsic ``call(address, *args)`` that calls, from compiled code, the kernel at
    `address` (`address_of`) with args and returns its intp; the callee's exceptions
    propagate.

    Parameters
    ----------
    name : str
        The intrinsic's name, for error messages.
    names : tuple of str
        The callee's argument names.
    fixed : callable
        ``fixed()`` -> the type each argument must have (None: any), as the callee was
        compiled for (`address_of`); called at typing time.

    Returns
    -------
    numba intrinsic
        A call whose argument types differ from `fixed` raises TypingError at compile
        time: the callee would read its arguments wrongly.
    """

    def typer(typingctx, address, *args):
        if not isinstance(address, types.Integer):
            raise TypingError(f"{name}: the address must be an integer, got {address}")
        if len(args) != len(names):
            raise TypingError(f"{name}: {len(names)} arguments after the address, got {len(args)}")
        for arg, got, want in zip(names, args, fixed()):
            if want is not None and got != want:
                raise TypingError(f"{name}: {arg} must be {want}, got {got}")

        def codegen(context, builder, signature, llargs):
            fnty = context.call_conv.get_function_type(types.intp, args)
            fn = builder.inttoptr(llargs[0], fnty.as_pointer())
            status, res = context.call_conv.call_function(builder, fn, types.intp, args, llargs[1:])
            with builder.if_then(status.is_error, likely=False):
                context.call_conv.return_status_propagate(builder, status)
            return res

        return types.intp(address, *args), codegen

    typer.__name__ = typer.__qualname__ = name
    # numba folds the call's arguments by this signature when lowering it: named ones, as
    # a starred parameter would be lowered as one tuple argument
    typer.__signature__ = inspect.Signature(
        [
            inspect.Parameter(n, inspect.Parameter.POSITIONAL_OR_KEYWORD)
            for n in ("typingctx", "address", *names)
        ]
    )
    return intrinsic(typer)
