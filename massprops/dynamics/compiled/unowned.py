"""`unowned`: views of arrays (or of tuples of arrays, nested) that numba does not reference-count.

numba counts references to every array a compiled function holds, with atomic operations; a
function that calls another keeps an increment and a decrement for every array it receives
(numba's pruning cannot prove the callee leaves them alone). The systems' kernels pass a program
of 21 arrays and a workspace of ~40 down through a dozen calls per right-hand side: measured,
that bookkeeping took ~90 % of an evaluation (1.3 µs of a 2-body `applied` that computes for
15 ns). A view with no meminfo makes each count a null test. The caller must keep the owned
arrays alive while the views are used (pass them along, as `systems_kernel`'s step entries do).

`by_ref` and `at`: a tuple passed by pointer. numba passes a tuple argument as one machine
argument per field of every array in it (~600 for the program and workspace); a call that is not
inlined then costs ~0.2 µs in copies alone, however little the callee computes (measured on
`systems_loads.applied`: 340 ns by tuples, 110 ns by pointer, for ~10 ns of arithmetic).
"""

from __future__ import annotations

from numba.core import cgutils, types
from numba.extending import intrinsic


def _strip(context, builder, ty, value):
    if isinstance(ty, types.Array):
        src = context.make_array(ty)(context, builder, value)
        out = context.make_array(ty)(context, builder)
        for name in ("nitems", "itemsize", "data", "shape", "strides", "parent"):
            setattr(out, name, getattr(src, name))
        out.meminfo = context.get_constant_null(types.MemInfoPointer(ty.dtype))
        return out._getvalue()
    if isinstance(ty, types.BaseTuple):
        items = [_strip(context, builder, t, builder.extract_value(value, i))
                 for i, t in enumerate(ty)]
        return context.make_tuple(builder, ty, items)
    return value


@intrinsic
def unowned(typingctx, x):
    """x (an array, or a tuple of arrays and scalars, nested) as views without a meminfo."""
    def codegen(context, builder, signature, args):
        return _strip(context, builder, signature.args[0], args[0])

    return x(x), codegen



@intrinsic
def by_ref(typingctx, x):
    """A pointer to `unowned` views of x, kept in the caller's frame: pass it down instead of a
    large tuple, which numba passes as one argument per array field (~10 words an array; the
    program and workspace tuples are ~600). `at` reads one item back. Valid only while the
    calling function runs (the copy is on its stack) and its owners live."""
    def codegen(context, builder, signature, args):
        slot = cgutils.alloca_once(builder, context.get_value_type(signature.args[0]))
        builder.store(_strip(context, builder, signature.args[0], args[0]), slot)
        return slot

    return types.CPointer(x)(x), codegen


@intrinsic
def at(typingctx, ptr, index):
    """Item ``index`` (a literal int) of the tuple `by_ref` pointed to, loading that item only
    (a view numba does not count: `by_ref` stored it unowned)."""
    if not isinstance(index, types.IntegerLiteral):
        return None
    k = index.literal_value
    item = ptr.dtype[k]

    def codegen(context, builder, signature, args):
        return builder.load(cgutils.gep_inbounds(builder, args[0], 0, k))

    return item(ptr, index), codegen
