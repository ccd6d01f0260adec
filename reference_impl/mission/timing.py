"""Timeouts and retry limits of the Mission Protocol.

Defaults are the spec's recommendation (seed 000, "Timeouts and Retries"): 1500 ms for a
response in general, 250 ms for mission items, at most 5 retries. Profiles override them
as data (PX4 and ArduPilot use other values: VARIANTS.md P3, A5).
"""

from __future__ import annotations

from dataclasses import dataclass, replace


@dataclass(frozen=True)
class Timings:
    default_timeout: float = 1.5   # s: wait for a response to COUNT, REQUEST_LIST, CLEAR_ALL, ...
    item_timeout: float = 0.25     # s: vehicle's wait for the item it requested
    max_retries: int = 5           # resends of one message before the operation is given up
    # s: a vehicle that gives an upload up only after this long without any message from its
    # partner, whatever its retry count (PX4 5 s, ArduPilot 8 s); None: after max_retries.
    protocol_timeout: float | None = None

    def __post_init__(self) -> None:
        if self.default_timeout <= 0 or self.item_timeout <= 0:
            raise ValueError("timeouts must be positive")
        if self.max_retries < 0:
            raise ValueError("max_retries must be >= 0")
        if self.protocol_timeout is not None and self.protocol_timeout <= 0:
            raise ValueError("protocol_timeout must be positive")

    def scaled(self, factor: float) -> "Timings":
        """Every deadline stretched by `factor` (slow links); retry counts unchanged."""
        protocol = None if self.protocol_timeout is None else self.protocol_timeout * factor
        return replace(self, default_timeout=self.default_timeout * factor,
                       item_timeout=self.item_timeout * factor, protocol_timeout=protocol)
