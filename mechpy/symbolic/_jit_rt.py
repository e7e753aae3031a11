"""What the numba modules of :mod:`mechpy.symbolic.jit` import: stack arrays.

``stack_f64(n)`` and ``stack_intc(n)`` return a pointer to n doubles / C ints
on the calling function's stack (LLVM alloca; n a literal integer), so that
the generated cfuncs keep their scratch as the C build keeps its local arrays:
no allocation per call.  Imported only by those modules (it imports numba).
"""
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

__all__ = ["stack_f64", "stack_intc"]


def _typer(ty, size):
    if not isinstance(size, types.IntegerLiteral):
        return None
    n = max(int(size.literal_value), 1)

    def impl(context, builder, sig, args):
        return cgutils.alloca_once(builder, context.get_value_type(ty), size=n)
    return types.CPointer(ty)(size), impl


@intrinsic
def stack_f64(typingctx, size):
    return _typer(types.float64, size)


@intrinsic
def stack_intc(typingctx, size):
    return _typer(types.intc, size)
