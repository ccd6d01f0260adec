"""Edge values: the float32 and integer values that break parsers, validators and the
float-to-integer conversions after them, for the fuzzers to put in every numeric field.

`edge_f32` draws any float32 a field can carry, biased to NaN, +-inf, subnormals, +-FLT_MAX and
`OUT_OF_RANGE`: floats a float32 carries exactly that no integer the receiver converts them to
can hold, each with the conversion it breaks. `edge_ints` biases an integer range to its ends.
"""

from __future__ import annotations

import math
import struct

from hypothesis import strategies as st

from mavconform.reference_impl.mission.items import INT32_MAX, INT32_MIN


def _f32(bits: int) -> float:
    return struct.unpack("<f", struct.pack("<I", bits))[0]


FLT_MAX = _f32(0x7F7FFFFF)
FLT_MIN_NORMAL = _f32(0x00800000)
FLT_SUBNORMAL_MIN = _f32(0x00000001)
FLT_SUBNORMAL_MAX = _f32(0x007FFFFF)
F32_EDGES = (float("nan"), float("inf"), float("-inf"), 0.0, -0.0, 1.0, -1.0, FLT_MAX, -FLT_MAX,
             FLT_MIN_NORMAL, FLT_SUBNORMAL_MIN, -FLT_SUBNORMAL_MIN, FLT_SUBNORMAL_MAX, _f32(0x7FC00001))

# Floats a float32 field carries exactly (so the wire delivers them unchanged) that no
# integer the receiver converts them to can hold. Autopilots turn MISSION_ITEM's floats into
# integers: latitude/longitude degrees * 1e7 into int32 degE7, local metres * 1e4 into
# int32, altitudes into int32 cm or mm, params used as indices or counts (DO_JUMP's target
# seq and repeat count, a fence polygon's vertex count) into int32/uint16/uint32. In C a
# float-to-int conversion of a value out of the integer's range (NaN and +-inf included) is
# undefined behaviour: on ARM it saturates, on x86 it gives INT_MIN, either way a stored
# value nobody sent. Each value with the conversion it breaks:
OUT_OF_RANGE: tuple[tuple[float, str], ...] = (
    (math.nan, "no integer at all; and every comparison with it is false, so a range check "
               "written as `v < lo || v > hi` lets it through"),
    (math.inf, "no integer: converting it is undefined in C, so a range check done after the "
               "conversion checks INT32_MIN (x86) or INT32_MAX (ARM) instead"),
    (-math.inf, "as +inf, downwards"),
    (1e10, "2^10 * 5^10, exact in float32: overflows int32 in every conversion (degE7 1e17, "
           "local 1e14, cm 1e12, mm 1e13, or taken as a plain integer)"),
    (-1e10, "as 1e10, downwards"),
    (215.0, "the first whole degree whose degE7 overflows int32 (2.15e9 > INT32_MAX; the limit "
            "is 214.7483647 deg): a longitude/latitude check done after the conversion sees a "
            "wrapped value"),
    (-215.0, "as 215, downwards (-2.15e9 < INT32_MIN)"),
    (214749.0, "the first whole metre whose local-frame value (metres * 1e4) overflows int32 "
               "(2147490000 > INT32_MAX); fits a plain int32, so only the scaled path breaks"),
    (2147484.0, "the first whole metre whose altitude in mm overflows int32 (2147484000)"),
    (21474838.0, "the first float32 whole metre whose altitude in cm overflows int32 "
                 "(2147483800; 21474837 is no float32)"),
    (65536.0, "UINT16_MAX + 1: a seq, jump target or count kept in 16 bits wraps to 0"),
    (2.0**31, "INT32_MAX + 1: an index or count kept in int32 overflows by one (and "
              "(float)INT32_MAX rounds to it, so `v <= (float)INT32_MAX` lets it through)"),
    (-2.0**31 - 256, "the float32 just below INT32_MIN (float32 spacing there is 256): "
                     "overflows int32 downwards; INT32_MIN itself still fits"),
    (3e9, "fits uint32 but not int32: a signed/unsigned mix-up stores it negative"),
    (2.0**32, "UINT32_MAX + 1: overflows uint32 too"),
    (FLT_MAX, "the largest finite float32: overflows every integer, and * 1e7 in float32 "
              "arithmetic is inf"),
    (-FLT_MAX, "as FLT_MAX, downwards"),
)
OUT_OF_RANGE_F32: tuple[float, ...] = tuple(v for v, _ in OUT_OF_RANGE)
out_of_range_f32 = st.sampled_from(OUT_OF_RANGE_F32)

subnormal_f32 = st.floats(-FLT_MIN_NORMAL, FLT_MIN_NORMAL, width=32, exclude_min=True,
                          exclude_max=True).filter(lambda v: v != 0.0)
# Every float32 a field can carry, biased to the values that break parsers, validators and
# the float-to-integer conversions after them (`OUT_OF_RANGE`; its NaN, +-inf and +-FLT_MAX
# are edges already). A second NaN branch here made two same-seed searches in one process
# shrink differently (seen with Hypothesis 6.170, whose shrinker compares values nested in
# dicts with ==, and NaN != NaN), so only the values F32_EDGES lacks are added.
_BEYOND_EDGES = tuple(v for v in OUT_OF_RANGE_F32 if v == v and v not in F32_EDGES)
edge_f32 = st.one_of(st.sampled_from(F32_EDGES), st.sampled_from(_BEYOND_EDGES), subnormal_f32,
                     st.floats(width=32))


def edge_ints(lo: int, hi: int, *extra: int) -> st.SearchStrategy[int]:
    """Integers in [lo, hi], biased to both ends, -1/0/1 and the given values."""
    marks = sorted({v for v in (lo, lo + 1, -1, 0, 1, hi - 1, hi, *extra) if lo <= v <= hi})
    return st.one_of(st.sampled_from(marks), st.integers(lo, hi))


edge_u8 = edge_ints(0, 255, 2, 127, 128)
edge_u16 = edge_ints(0, 65535, 255, 256, 32767, 32768)
edge_u32 = edge_ints(0, 2**32 - 1, 2**31)
# x/y: int32 extremes and the first values past +-90 / +-180 degrees in degE7.
edge_i32 = edge_ints(INT32_MIN, INT32_MAX, 900_000_000, 900_000_001, -900_000_001,
                     1_800_000_000, 1_800_000_001, -1_800_000_001)
