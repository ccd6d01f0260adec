"""C's float-to-integer conversions as x86-64 builds do them, for models of autopilot storage.

A float assigned to an integer field is converted by cvttss2si/cvttsd2si into a 32-bit (or,
for uint32 and unsigned enums, 64-bit) register: truncated toward zero, and NaN or a value out
of the register's range gives its minimum (INT32_MIN); a narrower field keeps the low bits. So
-1.0 stored in a uint8 reads back 255, in a uint16 65535, and NaN in either reads back 0.
ArduPilot's AP_Mission (ardupilot_commands.py), PX4's mission_item_s (px4_storage.py), INAV's
waypoint record (store.py) and the profiles' value checks (validation.py) all convert this way.
"""

from __future__ import annotations

from typing import Callable

Number = float | int


def cvtt(value: float, bits: int) -> int:
    """cvttss2si into a `bits`-wide register: truncate; NaN or out of range -> its minimum."""
    limit = 2 ** (bits - 1)
    if value != value or not -limit <= value < limit:
        return -limit
    return int(value)


def wrap(value: int, bits: int, signed: bool) -> int:
    """The low `bits` of `value`, read as signed or unsigned."""
    value &= (1 << bits) - 1
    return value - (1 << bits) if signed and value >> (bits - 1) else value


def int_conv(bits: int, signed: bool, via: int = 32) -> Callable[[Number], int]:
    """The conversion of a float (an int passes as it is) to a `bits`-wide field."""
    def conv(value: Number) -> int:
        raw = value if isinstance(value, int) else cvtt(value, via)
        return wrap(raw, bits, signed)
    return conv


u8, i8, u16, i16 = int_conv(8, False), int_conv(8, True), int_conv(16, False), int_conv(16, True)
u16_via64 = int_conv(16, False, via=64)  # an unsigned enum of 16 bits: 64-bit conversion
u32 = int_conv(32, False, via=64)
i32 = int_conv(32, True)
