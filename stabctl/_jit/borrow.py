"""Arrays without a reference count inside a kernel (`borrowed`), for the hot loops.

numba counts the references of every array a kernel passes to another kernel or binds to a
variable: an atomic increment and decrement of the array's meminfo (``NRT_incref`` /
``NRT_decref``).  LLVM's reference-count pruning (llvmlite's ``RefPrunePass``) removes a
pair only where no other decrement lies between them and every path reaches the
decrement, which the per-element calls of the model kernels do not meet (a branch around a
call, a raise path, a column view such as ``dx[:, k]``).  On ACTIVSg2000 (334 machines,
330 exciters, 329 stabilisers, 304 governors) one evaluation made about 11 000 increments
and as many decrements, half of a run's time (``perf``, 2026-11-27).

A borrowed array is the same view (data, shape, strides) with no meminfo: numba's
reference counting skips it (``NRT_incref`` of NULL returns at once, and LLVM folds the
call away).  It is valid only while its owner is alive, so a kernel borrows only its own
arguments (which its caller holds for the whole call) and never returns or stores a
borrowed array.
"""

from __future__ import annotations

from numba import types
from numba.core import cgutils
from numba.extending import intrinsic


def _borrow(context, builder, typ, value):
    """The LLVM value of `value` (numba type `typ`) with every array in it (recursively
    through tuples and NamedTuples) given a NULL meminfo and parent."""
    if isinstance(typ, types.Array):
        src = context.make_array(typ)(context, builder, value)
        dst = context.make_array(typ)(context, builder)
        for name in ("nitems", "itemsize", "data", "shape", "strides"):
            setattr(dst, name, getattr(src, name))
        dst.meminfo = cgutils.get_null_value(dst.meminfo.type)
        dst.parent = cgutils.get_null_value(dst.parent.type)
        return dst._getvalue()
    if isinstance(typ, types.BaseTuple):
        out = value
        for j, member in enumerate(typ):
            item = builder.extract_value(value, j)
            out = builder.insert_value(out, _borrow(context, builder, member, item), j)
        return out
    return value


@intrinsic
def borrowed(typingctx, value):
    """``value`` with every array in it borrowed: the same views, not reference-counted.

    Parameters
    ----------
    value : ndarray, tuple or NamedTuple (nested), or any other value
        A kernel's argument (its caller keeps it alive for the whole call).

    Returns
    -------
    same type as value
        Arrays (also inside tuples) share their data and layout with value's and carry
        no meminfo; other values unchanged.  Never return or store it beyond the call.
    """

    def codegen(context, builder, signature, args):
        return _borrow(context, builder, signature.args[0], args[0])

    return value(value), codegen
