"""CPython's ``math.dist``, ``math.fsum`` and ``round(x, ndigits)``, compiled, bitwise.

The frame-free seeds of the matcher (:mod:`._seeds`) choose base entries and order
correspondence hypotheses by distances rounded to a relative precision; those choices were
made, and are specified, with Python's float functions. These are their algorithms for
compiled loops, giving the same bits for every input (oracles: ``tests/metrics/test_seeds.py``):

* :func:`dist` is ``math.dist`` of two 2-D points: CPython's ``vector_norm`` (scale by a power
  of two, square and accumulate in double-length arithmetic, one differential correction of
  the square root), not a plain ``sqrt(dx*dx + dz*dz)``, which differs in the last bit;
  subnormal differences (below ``2**-1022`` m) go to Python's own;
* :func:`fsum` is ``math.fsum`` (Shewchuk's exact partials, correctly rounded, half-even
  across partials) for finite values that cannot overflow; other input goes to Python's own;
* :func:`round_half_even` is ``round(x, ndigits)``: the exact decimal rounding, half to even,
  of the binary value (``round(2.675, 2) == 2.67``), where ``numpy.round`` scales and rounds
  in floating point. Computed exactly while ``|x| * 10**ndigits < 2**52`` (the product and
  its error are exact, so the nearest integer and a tie are decided exactly, and dividing
  that integer by the exact power of ten is the correctly rounded decimal); outside that
  range (and for ``ndigits`` outside ``0..22``) Python's ``round`` is called.

Imported on first use only, with numba (:func:`._align.compiled`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from pytest_emrd.metrics._kernels import _POW10, _fma, _jit

#: Smallest positive normal double (``sys.float_info.min``).
_DBL_MIN = 2.2250738585072014e-308
#: Python calls back into the interpreter (``objmode``): compiled without ``nogil``.
_jit_gil = numba.njit(cache=True)
#: ``2**52``: below it, ``x * 10**ndigits`` and its rounding error decide the rounding exactly.
_EXACT_BELOW = 4503599627370496.0
#: Largest magnitude :func:`fsum` sums itself (no partial can overflow below it).
_FSUM_SAFE = 1e300


@_jit
def _two_sum(a: float, b: float) -> tuple[float, float]:
    """``a + b`` and its rounding error, for ``|a| >= |b|`` (CPython's ``dl_fast_sum``)."""
    x = a + b
    return x, (a - x) + b


@_jit
def _two_product(x: float, y: float) -> tuple[float, float]:
    """``x * y`` and its rounding error (CPython's ``dl_mul``)."""
    z = x * y
    return z, _fma(x, y, -z)


@_jit
def _norm(a: float, b: float, top: float) -> float:
    """CPython's ``vector_norm`` of ``(a, b)`` (both ``>= 0``, finite), ``top`` the larger,
    a normal number."""
    scale = math.ldexp(1.0, -math.frexp(top)[1])
    csum, frac1, frac2 = 1.0, 0.0, 0.0
    for x in (a * scale, b * scale):
        hi, lo = _two_product(x, x)
        csum, low = _two_sum(csum, hi)
        frac1 += lo
        frac2 += low
    h = math.sqrt(csum - 1.0 + (frac1 + frac2))
    hi, lo = _two_product(-h, h)
    csum, low = _two_sum(csum, hi)
    frac1 += lo
    frac2 += low
    x = csum - 1.0 + (frac1 + frac2)
    h += x / (2.0 * h)
    return h / scale


@_jit_gil
def dist(px: float, pz: float, qx: float, qz: float) -> float:
    """``math.dist((px, pz), (qx, qz))``: an infinite coordinate difference gives ``inf``, else
    a NaN gives NaN; differences below the smallest normal number go to Python's own."""
    a, b = abs(px - qx), abs(pz - qz)
    top = 0.0
    if a > top:
        top = a
    if b > top:
        top = b
    if math.isinf(top):
        return top
    if math.isnan(a) or math.isnan(b):
        return np.nan
    if top == 0.0:
        return top
    if top < _DBL_MIN:
        with numba.objmode(d="float64"):
            d = math.dist((px, pz), (qx, qz))
        return d
    return _norm(a, b, top)


@_jit_gil
def fsum(xs: np.ndarray) -> float:
    """``math.fsum(xs)`` (a 1-D array): CPython's partials, the last rounding half-even across
    partials. Values not finite, or large enough for a partial to overflow, are summed by
    Python's ``math.fsum`` itself (its infinities, NaN and errors)."""
    n = xs.shape[0]
    for i in range(n):
        if not abs(xs[i]) <= _FSUM_SAFE:
            with numba.objmode(total="float64"):
                total = math.fsum(xs.tolist())
            return total
    partials = np.empty(n + 1)
    used = 0
    for q in range(n):
        x = xs[q]
        i = 0
        for j in range(used):
            y = partials[j]
            if abs(x) < abs(y):
                x, y = y, x
            hi = x + y
            lo = y - (hi - x)
            if lo != 0.0:
                partials[i] = lo
                i += 1
            x = hi
        used = i
        if x != 0.0:
            partials[used] = x
            used += 1
    hi = 0.0
    if used > 0:
        used -= 1
        hi = partials[used]
        lo = 0.0
        while used > 0:
            x = hi
            used -= 1
            y = partials[used]
            hi = x + y
            lo = y - (hi - x)
            if lo != 0.0:
                break
        if used > 0 and (
            (lo < 0.0 and partials[used - 1] < 0.0) or (lo > 0.0 and partials[used - 1] > 0.0)
        ):
            y = lo * 2.0
            x = hi + y
            if y == x - hi:
                hi = x
    return hi


@_jit_gil
def round_half_even(x: float, ndigits: int) -> float:
    """``round(x, ndigits)`` (Python's, correctly rounded; see the module docstring)."""
    if not math.isfinite(x):
        return x
    if 0 <= ndigits <= 22:
        f = _POW10[ndigits]
        p = x * f
        if abs(p) < _EXACT_BELOW:
            err = _fma(x, f, -p)  # x * f == p + err exactly
            # p - r is exact, and unless it is -0.5 or 0.5 at least ulp(p) > |err| away
            # from them; at a tie of p, rint took the even side, which err may overturn
            r = np.rint(p)
            if p - r == 0.5 and err > 0.0:
                r += 1.0
            elif p - r == -0.5 and err < 0.0:
                r -= 1.0
            return r / f
    with numba.objmode(rounded="float64"):
        rounded = round(x, ndigits)
    return rounded
