"""A finding replayed with its capture: the MCAP beside the case, and the exchange the
report draws as a sequence diagram, one lane per peer."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import Any

from mavconform.conformance.harness.exchange import MAX_EVENTS, message_fields
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.messages import is_vehicle_heartbeat
from mavconform.reference_impl.net.capture import McapCapture
from mavconform.reference_impl.net.sim import CaptureRecord
from mavconform.reference_impl.wire.codec import FrameDecoder

from .case import MALFORMED, Case, Violation


def replay_recorded(mode: ModuleType, case: Case,
                    mcap: Path | None) -> tuple[Violation | None, list[dict[str, Any]]]:
    recorder = ExchangeRecorder()
    capture = McapCapture(mcap) if mcap is not None else None

    def hook(record: CaptureRecord) -> None:
        recorder(record)
        if capture is not None:
            capture(record)

    def mark(label: str, *, clock: Any = None, level: str = "info") -> None:
        recorder.mark(label, clock=clock, level=level)
        if capture is not None:
            capture.mark(label, clock=clock, level=level)

    hook.mark = mark   # type: ignore[attr-defined]  # step markers: a note in the exchange and the capture
    try:
        violation = mode.replay(case, capture=hook)
    except UsageError:
        raise
    except MALFORMED as exc:
        raise UsageError(f"the {case.mode} case for {case.target} has a malformed step "
                         f"({type(exc).__name__}: {exc})") from None
    finally:
        if capture is not None:
            capture.close()
    return violation, recorder.events


class ExchangeRecorder:
    """Capture records -> the run document's exchange events, one lane per peer.

    The target is the in-process vehicle (the node named `vehicle`) or, over UDP, the side
    whose HEARTBEAT names an autopilot: what it sends is `rx` from the lane of the peer it
    sends to; everything else (the fuzzer's GCS, a second GCS, raw bytes) is `tx` on the
    sender's lane. Lanes are given at the end, when the target is known, since it may speak
    before its first HEARTBEAT. Bytes that do not decode are one note each, so garbage shows
    as garbage; `mark` (a replay's step markers) adds a note where each step starts."""

    IN_PROCESS_TARGET = "vehicle"
    LANES = {"a": "tester", "gcs": "tester", "b": "gcs-b"}   # the fuzzers' node names

    def __init__(self) -> None:
        self._raw: list[tuple[float, Any, Any, str, str, dict[str, Any]]] = []
        self.omitted = 0
        self._decoders: dict[Any, FrameDecoder] = {}
        self._target: Any = None
        self._t0: float | None = None

    def __call__(self, record: CaptureRecord) -> None:
        if record.kind == "rx":
            return                                  # each datagram once: when it was sent
        t = self._time(record.time)
        if self._target is None and record.src == self.IN_PROCESS_TARGET:
            self._target = record.src
        if record.kind == "drop":
            self._add(t, record.src, record.dst, "note", f"link dropped {len(record.data)} bytes", {})
            return
        decoder = self._decoders.setdefault(record.src, FrameDecoder())
        decoded = 0
        for frame in decoder.feed(record.data):
            msg = getattr(frame, "msg", None)
            if msg is None:                          # a DecodeError
                continue
            decoded += 1
            name = msg.get_type()
            if self._target is None and is_vehicle_heartbeat(msg):
                self._target = record.src
            if name in ("HEARTBEAT", "GLOBAL_POSITION_INT"):
                continue
            self._add(t, record.src, record.dst, "", name, message_fields(msg))
        if not decoded:
            self._add(t, record.src, record.dst, "note",
                      f"{len(record.data)} bytes that decode to no frame: {record.data[:24].hex()}"
                      + ("..." if len(record.data) > 24 else ""), {})

    def mark(self, label: str, *, clock: Any = None, level: str = "info") -> None:
        """A note where a replay step starts (the capture's `mark` signature)."""
        t = self._time(clock.now()) if clock is not None else (self._raw[-1][0] if self._raw else 0.0)
        self._add(t, None, None, "note", label, {})

    @property
    def events(self) -> list[dict[str, Any]]:
        out = []
        for t, src, dst, kind, msg, fields in self._raw:
            if kind == "note":
                out.append({"t": t, "dir": "note", "peer": self._lane(src if src != self._target else dst),
                            "msg": msg, "fields": fields})
            elif src == self._target:
                out.append({"t": t, "dir": "rx", "peer": self._lane(dst), "msg": msg, "fields": fields})
            else:
                out.append({"t": t, "dir": "tx", "peer": self._lane(src), "msg": msg, "fields": fields})
        if self.omitted:
            last = out[-1]["t"] if out else 0.0
            out.append({"t": last, "dir": "note", "peer": "fuzzer",
                        "msg": f"... {self.omitted} more events in the MCAP capture", "fields": {}})
        return out

    def _time(self, now: float) -> float:
        if self._t0 is None:
            self._t0 = now
        return round(now - self._t0, 6)

    def _lane(self, address: Any) -> str:
        if address is None:
            return "fuzzer"
        if address == self._target:        # the target's own lane is the diagram's middle
            return "target"
        if isinstance(address, str):
            return self.LANES.get(address, address)
        return "tester" if self._target is not None else ":".join(map(str, address))

    def _add(self, t: float, src: Any, dst: Any, kind: str, msg: str, fields: dict[str, Any]) -> None:
        if len(self._raw) >= MAX_EVENTS:      # the MCAP keeps them all
            self.omitted += 1
            return
        self._raw.append((t, src, dst, kind, msg, fields))
