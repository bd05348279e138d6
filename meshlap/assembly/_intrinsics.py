"""Compiled building blocks of the kernels: an atomic counter, a fused multiply-add, a
vectorizable exp(−x) (libm's exp does not vectorize), accurate to about an ulp, and the
diagonal that makes a Laplacian's row sum to zero."""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from .._jit import jit

__all__ = []


@intrinsic
def _bits_as_float(typingctx, bits):
    """Reinterpret the 64 bits of an int64 as a float64."""
    sig = types.float64(types.int64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return sig, codegen


@intrinsic
def _float_as_bits(typingctx, x):
    """Reinterpret the 64 bits of a float64 as an int64."""
    sig = types.int64(types.float64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return sig, codegen


@intrinsic
def _muladd(typingctx, a, b, c):
    """a * b + c, fused where the CPU has FMA (llvm.fmuladd), else a multiply and an add."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        dbl = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fmuladd", [dbl], ir.FunctionType(dbl, [dbl] * 3))
        return builder.call(fn, args)

    return sig, codegen


@intrinsic
def _fetch_add(typingctx, arr, idx, val):
    """Atomically add ``val`` to ``arr[idx]`` (an int64 array) and return the old value."""
    sig = types.int64(arr, types.intp, types.int64)

    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, args[0])
        ptr = cgutils.get_item_pointer(context, builder, aryty, ary, [args[1]])
        return builder.atomic_rmw("add", ptr, args[2], "monotonic")

    return sig, codegen


_LOG2E = 1.4426950408889634
# ln 2 split so that k * _LN2_HI is exact for |k| < 2^11 (Cody and Waite's reduction)
_LN2_HI = 6.93147180369123816490e-01
_LN2_LO = 1.90821492927058770002e-10
_SHIFTER = 4503599627371519.0  # 2^52 + 1023


@jit(inline="always")
def _exp_neg(x):
    # exp(x) for x <= 0 (0 below -708): x = k ln2 + t with |t| <= ln2/2, exp(t) by its Taylor
    # series to t^13 (truncation < 1e-17), 2^k from exponent bits. k stays a float and
    # reaches the bits through the 2^52 shifter, since AVX2 has no vector double -> int64.
    xc = max(x, -708.0)
    k = np.floor(xc * _LOG2E + 0.5)
    t = (xc - k * _LN2_HI) - k * _LN2_LO
    p = 1.6059043836821613e-10
    p = _muladd(p, t, 2.08767569878681e-09)
    p = _muladd(p, t, 2.505210838544172e-08)
    p = _muladd(p, t, 2.755731922398589e-07)
    p = _muladd(p, t, 2.7557319223985893e-06)
    p = _muladd(p, t, 2.48015873015873e-05)
    p = _muladd(p, t, 1.984126984126984e-04)
    p = _muladd(p, t, 1.388888888888889e-03)
    p = _muladd(p, t, 8.333333333333333e-03)
    p = _muladd(p, t, 4.1666666666666664e-02)
    p = _muladd(p, t, 1.6666666666666666e-01)
    p = _muladd(p, t, 0.5)
    p = _muladd(p, t, 1.0)
    p = _muladd(p, t, 1.0)
    # the low mantissa bits of 2^52 + 1023 + k hold the biased exponent 1023 + k (in [1, 1023])
    scale = _bits_as_float(_float_as_bits(k + _SHIFTER) << 52)
    return p * scale if x >= -708.0 else 0.0


@jit(inline="always")
def zero_row_sum(q, indptr, indices, data):  # pragma: no cover
    """Set row q's diagonal entry (where the row has one) to minus the sum of its other
    entries, added in their stored order, so that the row sums to zero."""
    diag = -1
    s = 0.0
    for e in range(indptr[q], indptr[q + 1]):
        if indices[e] == q:
            diag = e
        else:
            s += data[e]
    if diag >= 0:
        data[diag] = -s
