"""A NamedTuple of arrays as two flat buffers, so that a call into numba unboxes a few
arrays rather than seventy (each costs a boxing check on entry).

``pack(arrays)`` returns (ints, floats, index): every int64 field lives in ``ints``,
every float64 field in ``floats``; row k of ``index`` is (offset, size, ndim, shape...)
of field k. ``views(cls, arrays, ints, floats, index)`` rebuilds the NamedTuple from views into the
buffers (numpy). In numba, ``view1`` … ``view4`` give one field by its number, named by
``fields(cls)`` (an IntEnum, which numba reads as a constant); the kernel keeps the
views in local variables, since numba compiles tuples of many arrays very slowly. A view
is built directly from the index (no slicing or reshaping checks: about 60 views cost a
twentieth of a small robot's evaluation that way) and, like ``borrowed``, carries no
reference count. ``borrowed`` drops an array's reference count for the length of a
kernel call: every view and slice of a counted array costs two atomic operations, a
fifth of the kernel's time.
"""

import enum

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from .bodies import OPTIONS

MAX_NDIM = 4


def fields(cls):
    """The field numbers of a NamedTuple class, as an IntEnum."""
    return enum.IntEnum(f"{cls.__name__}Field", {name: i for i, name in enumerate(cls._fields)})


def pack(arrays):
    index = np.zeros((len(arrays), 3 + MAX_NDIM), dtype=np.int64)
    parts = {np.int64: [], np.float64: []}
    sizes = {np.int64: 0, np.float64: 0}
    for k, a in enumerate(arrays):
        kind = np.int64 if np.issubdtype(a.dtype, np.integer) else np.float64
        index[k, :3] = sizes[kind], a.size, a.ndim
        index[k, 3:3 + a.ndim] = a.shape
        parts[kind].append(np.ascontiguousarray(a, dtype=kind).ravel())
        sizes[kind] += a.size
    ints, floats = (np.concatenate([np.zeros(0, kind)] + parts[kind]) for kind in (np.int64, np.float64))
    return ints, floats, index


def views(cls, arrays, ints, floats, index):
    """``cls`` (a NamedTuple class) of views into the buffers, typed like ``arrays``."""
    out = []
    for k, a in enumerate(arrays):
        buf = ints if np.issubdtype(a.dtype, np.integer) else floats
        offset, size, ndim = index[k, :3]
        out.append(buf[offset:offset + size].reshape(tuple(index[k, 3:3 + ndim])))
    return cls(*out)


@intrinsic
def _view(typingctx, buf, offset, shape):
    """A C-contiguous array of ``shape`` at element ``offset`` of the 1-d ``buf``, without
    a reference count (as ``borrowed``) and without numba's slicing and reshaping checks:
    ``pack`` wrote the offsets and shapes, so they fit."""
    ndim = len(shape)
    layout = types.Array(buf.dtype, ndim, "C")

    def codegen(context, builder, signature, args):
        source = context.make_array(signature.args[0])(context, builder, args[0])
        dims = cgutils.unpack_tuple(builder, args[2], ndim)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(buf.dtype)))
        strides, stride = [], itemsize
        for dim in reversed(dims):
            strides.insert(0, stride)
            stride = builder.mul(stride, dim)
        out = context.make_array(layout)(context, builder)
        context.populate_array(out, data=builder.gep(source.data, [args[1]]), shape=dims, strides=strides,
                               itemsize=itemsize, meminfo=None)
        return out._getvalue()
    return layout(buf, types.intp, types.UniTuple(types.intp, ndim)), codegen


@njit(**OPTIONS)
def view1(buf, index, k):
    return _view(buf, index[k, 0], (index[k, 1],))


@njit(**OPTIONS)
def view2(buf, index, k):
    return _view(buf, index[k, 0], (index[k, 3], index[k, 4]))


@njit(**OPTIONS)
def view3(buf, index, k):
    return _view(buf, index[k, 0], (index[k, 3], index[k, 4], index[k, 5]))


@njit(**OPTIONS)
def view4(buf, index, k):
    return _view(buf, index[k, 0], (index[k, 3], index[k, 4], index[k, 5], index[k, 6]))


@intrinsic
def borrowed(typingctx, array):
    """The same array without its reference count (a null meminfo): views of it cost no
    atomic increments. Only for arrays that outlive the call, as the kernel's arguments."""
    def codegen(context, builder, signature, args):
        source = context.make_array(signature.args[0])(context, builder, args[0])
        out = context.make_array(signature.return_type)(context, builder)
        for field in ("parent", "nitems", "itemsize", "data", "shape", "strides"):
            setattr(out, field, getattr(source, field))
        out.meminfo = context.get_constant_null(types.MemInfoPointer(types.voidptr))
        return out._getvalue()
    return array(array), codegen
