"""Interop: the reference GCS against the PX4-like and ArduPilot-like vehicle profiles, and
the QGroundControl MockLink failure modes injected in front of any of them."""
