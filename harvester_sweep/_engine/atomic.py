"""An atomic counter for jitted code: the shared queue from which every thread of a
parallel call takes its next piece of work, so that the threads end together whatever
each piece costs (numba's ``prange`` deals each thread an equal block up front)."""

from __future__ import annotations

from numba import types
from numba.core import cgutils
from numba.extending import intrinsic


@intrinsic
def fetch_add(typingctx, counts, i):
    """``counts[i] += 1`` as one atomic operation (int64 array); returns the value before."""
    if not (isinstance(counts, types.Array) and counts.dtype == types.int64
            and isinstance(i, types.Integer)):
        return None

    def codegen(context, builder, signature, args):
        array, index = args
        ary = context.make_array(signature.args[0])(context, builder, array)
        index = context.cast(builder, index, signature.args[1], types.intp)
        pointer = cgutils.get_item_pointer(context, builder, signature.args[0], ary, [index])
        return builder.atomic_rmw("add", pointer, context.get_constant(types.int64, 1),
                                  "monotonic")

    return types.int64(counts, i), codegen
