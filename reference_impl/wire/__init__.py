"""Wire: the project's dialect and the frame codec (MAVLink 1/2, signing)."""

from .codec import FrameDecoder, FrameEncoder
from .frame import DecodeError, Frame, SignatureVerdict
from .signing import SigningKey

__all__ = ["DecodeError", "Frame", "FrameDecoder", "FrameEncoder", "SignatureVerdict", "SigningKey"]
