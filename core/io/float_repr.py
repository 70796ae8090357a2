"""Python's ``repr`` of float64 values, written by a compiled kernel: the text writer's
float columns without a Python call per value.

``repr`` gives the shortest decimal that reads back to the same double (the nearest of
those, ties to even), in fixed notation for 1e-4 <= |x| < 1e16 (``1.0``, ``0.0001``) and
otherwise as ``1e-05``, ``1.5e+16``; ``nan``, ``inf``, ``-inf``, ``-0.0``. The digits come
from Ryu (U. Adams, "Ryu: fast float-to-string conversion", PLDI 2018), which finds that
same shortest nearest decimal with 64-bit integer arithmetic and tables of powers of 5.
Every kernel's callees are in this file, so numba's cache stamp (the file's) covers them.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

_OPTS = dict(cache=True, nogil=True)
_MASK64 = (1 << 64) - 1
#: bits kept of each power of 5 (and of each inverse power of 5) in the tables
_POW5_BITS = 125
#: the widest repr of a float64 ("-2.2250738585072014e-308") or an int64 / uint64
REPR_WIDTH = 24
#: the kinds of column :func:`join_rows` writes
FLOAT64, INT64, UINT64, TEXT = 0, 1, 2, 3
_U1 = np.uint64(1)
_MANTISSA = np.uint64((1 << 52) - 1)
_HIDDEN = np.uint64(1 << 52)
_EXP_ALL = np.uint64(0x7FF0000000000000)
_SIGN = np.uint64(1 << 63)
_DOT, _MINUS, _ZERO = 46, 45, np.uint64(48)
_POWERS_OF_10 = np.array([10**i for i in range(20)], dtype=np.uint64)
_PAIRS = np.frombuffer("".join(f"{i:02d}" for i in range(100)).encode(), dtype=np.uint8)
_NAN, _INF, _ZERO_TEXT, _POINT_ZERO = (np.frombuffer(t, dtype=np.uint8) for t in (b"nan", b"inf", b"0.0", b"0."))


def _words(value: int) -> tuple[int, int]:
    """The (low, high) 64-bit words of a 128-bit integer."""
    return value & _MASK64, value >> 64


def _power_tables() -> tuple[np.ndarray, np.ndarray]:
    """Ryu's tables: 5^i cut to its top 125 bits (i < 326), and 2^(125 + bits(5^q) - 1) / 5^q
    rounded up (q < 292), each as (low, high) 64-bit words."""
    pos = [_words(5**i >> max(0, (5**i).bit_length() - _POW5_BITS) << max(0, _POW5_BITS - (5**i).bit_length()))
           for i in range(326)]
    inv = [_words((1 << ((5**q).bit_length() - 1 + _POW5_BITS)) // 5**q + 1) for q in range(292)]
    return np.array(pos, dtype=np.uint64), np.array(inv, dtype=np.uint64)


_POW5, _POW5_INV = _power_tables()


@njit(**_OPTS)
def _high_word(a, b):
    """The high 64-bit word of the 128-bit product of two uint64, from 32-bit halves."""
    half, low_half = np.uint64(32), np.uint64(0xFFFFFFFF)
    a_lo, a_hi, b_lo, b_hi = a & low_half, a >> half, b & low_half, b >> half
    mid1 = a_hi * b_lo + ((a_lo * b_lo) >> half)
    mid2 = a_lo * b_hi + (mid1 & low_half)
    return a_hi * b_hi + (mid1 >> half) + (mid2 >> half)


@njit(**_OPTS)
def _mul_shift(m, factor, shift):
    """(m * factor) >> shift for a 128-bit ``factor`` (low, high) and 64 < shift < 128."""
    high0 = _high_word(m, factor[0])
    low1, high1 = m * factor[1], _high_word(m, factor[1])
    total = high0 + low1
    if total < high0:
        high1 += _U1
    dist = np.uint64(shift - 64)
    return (high1 << (np.uint64(64) - dist)) | (total >> dist)


@njit(**_OPTS)
def _pow5_factor(value):
    """How many times 5 divides ``value`` (> 0)."""
    count = 0
    while value > 0 and value % np.uint64(5) == 0:
        value //= np.uint64(5)
        count += 1
    return count


@njit(**_OPTS)
def _pow5_bits(e):
    """The bit length of 5^e (0 <= e <= 3528), without computing 5^e."""
    return ((e * 1217359) >> 19) + 1


@njit(**_OPTS)
def _scaled_interval(m2, e2, even, mm_shift):
    """Ryu's step 3: the value and its rounding interval's ends scaled to integers
    (vr, vp, vm) by 10^-e10, whether the digits dropped in the scaling were all zero
    (for vm and vr), and e10."""
    mv = np.uint64(4) * m2
    vm_zeros = vr_zeros = False
    if e2 >= 0:
        q = max(0, ((e2 * 78913) >> 18) - 1)
        e10, shift, factor = q, -e2 + q + _POW5_BITS + _pow5_bits(q) - 1, _POW5_INV[q]
    else:
        q = max(0, ((-e2 * 732923) >> 20) - 1)
        i = -e2 - q
        e10, shift, factor = q + e2, q - (_pow5_bits(i) - _POW5_BITS), _POW5[i]
    vr = _mul_shift(mv, factor, shift)
    vp = _mul_shift(mv + np.uint64(2), factor, shift)
    vm = _mul_shift(mv - _U1 - mm_shift, factor, shift)
    if e2 >= 0 and q <= 21:
        if mv % np.uint64(5) == 0:
            vr_zeros = _pow5_factor(mv) >= q
        elif even:
            vm_zeros = _pow5_factor(mv - _U1 - mm_shift) >= q
        elif _pow5_factor(mv + np.uint64(2)) >= q:
            vp -= _U1
    elif e2 < 0 and q <= 1:
        vr_zeros = True
        if even:
            vm_zeros = (~(mv - _U1 - mm_shift) & _U1) >= q
        else:
            vp -= _U1
    elif e2 < 0 and q < 63:
        vr_zeros = (mv & ((_U1 << np.uint64(q - 1)) - _U1)) == 0
    return vr, vp, vm, vm_zeros, vr_zeros, e10


@njit(**_OPTS)
def _shortest(magnitude):
    """Ryu's steps 1-4 for a finite non-zero magnitude's bits: the digits (an integer) and
    the power of ten of the last one, of the shortest nearest decimal that reads back."""
    exponent = np.int64(magnitude >> np.uint64(52))
    m2 = magnitude & _MANTISSA
    e2 = 1 - 1023 - 52 - 2
    if exponent:
        m2 |= _HIDDEN
        e2 = exponent - 1023 - 52 - 2
    even = (m2 & _U1) == 0
    mm_shift = np.uint64(1 if m2 != _HIDDEN or exponent <= 1 else 0)
    vr, vp, vm, vm_zeros, vr_zeros, e10 = _scaled_interval(m2, e2, even, mm_shift)
    ten = np.uint64(10)
    removed, last = 0, np.uint64(0)
    while vp // ten > vm // ten:
        vm_zeros &= vm % ten == 0
        vr_zeros &= last == 0
        last = vr % ten
        vr, vp, vm = vr // ten, vp // ten, vm // ten
        removed += 1
    if vm_zeros:
        while vm % ten == 0:
            vr_zeros &= last == 0
            last = vr % ten
            vr, vp, vm = vr // ten, vp // ten, vm // ten
            removed += 1
    if vr_zeros and last == 5 and vr % np.uint64(2) == 0:
        last = np.uint64(4)  # exactly ...50000: round half to even
    up = (vr == vm and (not even or not vm_zeros)) or last >= 5
    return vr + np.uint64(1 if up else 0), e10 + removed


@njit(**_OPTS)
def _digit_count(value, most):
    """The decimal digits of ``value``, which has at most ``most`` (checked from the top:
    a double's shortest digits are mostly 16 or 17)."""
    count = most
    while count > 1 and value < _POWERS_OF_10[count - 1]:
        count -= 1
    return count


@njit(**_OPTS)
def _put_digits(value, count, out, at):
    """Write the last ``count`` decimal digits of ``value`` at ``at``, two at a time;
    returns the position after them."""
    pos = at + count
    hundred = np.uint64(100)
    while pos - at >= 2:
        pair = 2 * (value % hundred)
        value //= hundred
        out[pos - 1] = _PAIRS[pair + 1]
        out[pos - 2] = _PAIRS[pair]
        pos -= 2
    if pos > at:
        out[at] = _ZERO + value % np.uint64(10)
    return at + count


@njit(**_OPTS)
def _put_pointed(value, count, dot, out, at):
    """The ``count`` digits of ``value`` with a '.' after the first ``dot`` (0 < dot < count)."""
    _put_digits(value, count, out, at + 1)
    for k in range(dot):
        out[at + k] = out[at + k + 1]
    out[at + dot] = _DOT
    return at + count + 1


@njit(**_OPTS)
def _put_text(text, out, at):
    for k in range(len(text)):
        out[at + k] = text[k]
    return at + len(text)


@njit(**_OPTS)
def _put_exponent(power, out, at):
    """"e+16", "e-05", "e+300": the sign and at least two digits."""
    out[at] = 101
    out[at + 1] = _MINUS if power < 0 else 43
    power = abs(power)
    width = 3 if power >= 100 else 2
    for k in range(width - 1, -1, -1):
        out[at + 2 + k] = 48 + power % 10
        power //= 10
    return at + 2 + width


@njit(**_OPTS)
def _put_repr(bits, out, at):
    """Write repr() of the double whose bits are ``bits`` at ``at``; returns the end."""
    magnitude = bits & ~_SIGN
    if magnitude > _EXP_ALL:
        return _put_text(_NAN, out, at)
    if bits & _SIGN:
        out[at] = _MINUS
        at += 1
    if magnitude == _EXP_ALL:
        return _put_text(_INF, out, at)
    if magnitude == 0:
        return _put_text(_ZERO_TEXT, out, at)
    digits, power = _shortest(magnitude)
    count = _digit_count(digits, 17)
    point = power + count  # the value is 0.(digits) x 10^point
    if point <= -4 or point > 16:
        at = _put_pointed(digits, count, 1, out, at) if count > 1 else _put_digits(digits, 1, out, at)
        return _put_exponent(point - 1, out, at)
    if point <= 0:
        at = _put_text(_POINT_ZERO, out, at)
        for _ in range(-point):
            out[at] = _ZERO
            at += 1
        return _put_digits(digits, count, out, at)
    if point >= count:
        at = _put_digits(digits, count, out, at)
        for _ in range(point - count):
            out[at] = _ZERO
            at += 1
        return _put_text(_ZERO_TEXT[1:], out, at)
    return _put_pointed(digits, count, point, out, at)


@njit(**_OPTS)
def _put_integer(word, signed, out, at):
    """Write '%d' of ``word``, an int64 (``signed``) or a uint64 held as uint64 bits."""
    if signed and word & _SIGN:
        out[at] = _MINUS
        at += 1
        word = ~word + _U1  # the magnitude, also of -2^63
    return _put_digits(word, _digit_count(word, 20), out, at)


@njit(**_OPTS)
def join_rows(words, texts, kinds, delimiter, out):
    """Write rows of text into ``out`` (uint8, long enough); returns the bytes written.
    Column j of a row is, by ``kinds[j]``: FLOAT64, repr() of the double whose bits are
    ``words[row, j]``; INT64 or UINT64, '%d' of that word; TEXT, the NUL-padded bytes
    ``texts[row, j]``. Columns are separated by the bytes ``delimiter``, rows end in a newline."""
    at = 0
    for row in range(words.shape[0]):
        for j in range(len(kinds)):
            if j:
                at = _put_text(delimiter, out, at)
            if kinds[j] == FLOAT64:
                at = _put_repr(words[row, j], out, at)
            elif kinds[j] != TEXT:
                at = _put_integer(words[row, j], kinds[j] == INT64, out, at)
            else:
                k = 0
                while k < texts.shape[2] and texts[row, j, k]:
                    out[at] = texts[row, j, k]
                    at += 1
                    k += 1
        out[at] = 10
        at += 1
    return at


@njit(**_OPTS, parallel=True)
def join_blocks(words, texts, kinds, delimiter, out, block_rows, row_bytes):
    """:func:`join_rows` on blocks of ``block_rows`` rows in parallel, block b into
    ``out`` from b * block_rows * row_bytes (``row_bytes``: the most a row can take);
    returns the bytes written for each block."""
    n_blocks = (words.shape[0] + block_rows - 1) // block_rows
    written = np.zeros(n_blocks, dtype=np.int64)
    for b in prange(n_blocks):
        lo, hi = b * block_rows, min((b + 1) * block_rows, words.shape[0])
        written[b] = join_rows(words[lo:hi], texts[lo:hi], kinds, delimiter, out[lo * row_bytes : hi * row_bytes])
    return written
