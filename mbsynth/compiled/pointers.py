"""Compiled functions called through function pointers, so that a caller compiles once for
every callee of one signature (a model's generated function, a kernel variant) instead of
once per callee, and stays small (the callee's code is not linked into it).

``address(dispatcher, signature)`` compiles (or loads) the dispatcher for ``signature`` and
returns its two entry addresses; ``caster(signature)`` returns a numba intrinsic that turns
such a pair into a callable first-class function of that signature inside compiled code.
A call through it follows numba's own calling convention (the jit entry), as a direct call
does. The caller must keep the dispatcher alive while it calls the addresses.
"""

from numba import types
from numba.core import cgutils
from numba.experimental.function_type import _get_jit_address, _get_wrapper_address
from numba.extending import intrinsic

from ..core.memo import MEMO


@MEMO.function(1024)
def address(dispatcher, signature):
    """(C wrapper address, jit address) of ``dispatcher`` compiled for ``signature`` (a full
    numba signature, its return type included, which must be the one numba infers); kept,
    with the dispatcher, for the next Engine that asks (every run makes one)."""
    dispatcher.compile(signature.args)
    found = dispatcher.overloads[signature.args].signature.return_type
    if found != signature.return_type:
        raise TypeError(f"{dispatcher.py_func.__qualname__} returns {found}, not {signature.return_type}")
    return _get_wrapper_address(dispatcher, signature), _get_jit_address(dispatcher, signature)


def caster(signature):
    """An intrinsic (c_addr, jit_addr, selector) → a first-class function of the signature
    ``signature(type of selector)`` (a function of the numba type of the third argument, which
    is only read at compile time: a caller compiled per variant picks the callee's signature)."""

    @intrinsic
    def cast(typingctx, c_addr, jit_addr, selector):
        function = types.FunctionType(signature(selector))

        def codegen(context, builder, sig, args):
            made = cgutils.create_struct_proxy(function)(context, builder)
            pointer = context.get_value_type(types.voidptr)
            made.c_addr = builder.inttoptr(args[0], pointer)
            made.py_addr = context.get_constant_null(types.voidptr)
            made.jit_addr = builder.inttoptr(args[1], pointer)
            return made._getvalue()
        return function(types.int64, types.int64, selector), codegen

    return cast
