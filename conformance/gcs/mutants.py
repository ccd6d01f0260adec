"""Mutant reference GCSs: each breaks named GCS clauses, to prove the GCS checks can fail.

A mutant is the reference GCS (reference_impl/gcs.py) with one behaviour changed, almost
always by a `MissionClient` subclass that overrides one method, or by one `GcsConfig`
knob; the bugs are ones real ground stations and SDKs have had (MAVSDK, MAVProxy,
DroneKit, ...). `breaks` lists exactly the clauses the change fails: the negative-control
tests (tests/conformance/gcs/test_gcs_negative_controls.py) assert that each of them
fails on the mutant, that every other GCS clause passes, and that every GCS clause is
broken by some mutant. `build` has the `NodeAdapter` builder's signature. The set-current
mutants are in mutants_current.py, the addressing ones in mutants_routing.py; both register
here when this module is imported.
"""

from __future__ import annotations

import dataclasses
import struct
from dataclasses import dataclass
from typing import Any

from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionType, renumber
from mavconform.reference_impl.mission.results import Operation, Outcome
from mavconform.reference_impl.mission.timing import Timings
from mavconform.reference_impl.net.node import Address

from .adapters import GcsBuilder


@dataclass(frozen=True)
class GcsMutant:
    name: str
    description: str
    breaks: frozenset[str]
    build: GcsBuilder


GCS_MUTANTS: dict[str, GcsMutant] = {}


def gcs_mutant(name: str, description: str, breaks: set[str] | frozenset[str], build: GcsBuilder) -> GcsMutant:
    if name in GCS_MUTANTS:
        raise ValueError(f"duplicate GCS mutant {name!r}")
    made = GcsMutant(name, description, frozenset(breaks), build)
    GCS_MUTANTS[name] = made
    return made


# --- how a mutant client gets into the reference GCS (the one place) ---------------------------
class _MutantGcs(GcsNode):
    """The reference GCS, with its mission engine made by `client_class`."""

    def __init__(self, config: GcsConfig, remote: Address, client_class: type[MissionClient]) -> None:
        self._client_class = client_class
        super().__init__(config, remote=remote)

    def _make_client(self) -> None:
        super()._make_client()
        cfg, made = self.config, self.client
        self.client = self._client_class(cfg.system, cfg.component, self.target, cfg.timings,
                                         upload_int=made.upload_int, download_int=made.download_int,
                                         answer_request_with_int=made.answer_request_with_int,
                                         adaptations=self.adaptations)


def client_mutant(client_class: type[MissionClient] = MissionClient, **config: Any) -> GcsBuilder:
    """A builder for the reference GCS whose mission engine is `client_class`, with
    `GcsConfig` fields changed."""
    def build(base: GcsConfig, vehicle: Address) -> GcsNode:
        return _MutantGcs(dataclasses.replace(base, **config) if config else base, vehicle, client_class)
    return build


class _As:
    """A received message seen with some fields changed (what a careless GCS reads it as)."""

    def __init__(self, msg: Any, **fields: Any) -> None:
        self._msg, self._fields = msg, fields

    def __getattr__(self, name: str) -> Any:
        return self._fields[name] if name in self._fields else getattr(self._msg, name)


def _is_item(msg: Any) -> bool:
    return msg._type in (m.ITEM_INT, m.ITEM_FLOAT)


# --- resends and giving up ---------------------------------------------------------------------
class _SkipsResend(MissionClient):
    """Its timer runs (retries are counted, the operation is given up after them) but the
    resends `skipped` picks never go out."""

    def skipped(self, msg: Any) -> bool:
        raise NotImplementedError

    def poll(self, now: float) -> list[Any]:
        return [a for a in super().poll(now) if not (isinstance(a, Send) and self.skipped(a.msg))]


class _NoCountResend(_SkipsResend):
    def skipped(self, msg):
        return msg._type == "MISSION_COUNT"


class _NoListResend(_SkipsResend):
    def skipped(self, msg):
        return msg._type == "MISSION_REQUEST_LIST"


class _NoItemRequestResend(_SkipsResend):
    def skipped(self, msg):
        return msg._type in (m.REQUEST_INT, m.REQUEST_FLOAT)


class _NoClearResend(_SkipsResend):
    def skipped(self, msg):
        return msg._type == "MISSION_CLEAR_ALL"


class _NoLastItemResend(_SkipsResend):
    def skipped(self, msg):
        return _is_item(msg) and self._op is not None and msg.seq == self._op.count - 1


class _IgnoresLastRerequest(MissionClient):
    def _on_request(self, op, msg, now):
        if op.last_item_sent and msg.seq == op.count - 1:
            return []   # "already sent": waits for the final ACK only
        return super()._on_request(op, msg, now)


class _NeverGivesUp(MissionClient):
    def poll(self, now):
        if self._op is not None:
            self._op.consecutive = min(self._op.consecutive, self.timings.max_retries - 1)
        return super().poll(now)


gcs_mutant("no-count-resend", "never resends MISSION_COUNT (waits out its retries in silence)",
           {"MIS.G.UP.06", "MIS.G.TO.01"}, client_mutant(_NoCountResend))
gcs_mutant("no-last-item-resend", "never resends the last item when the final MISSION_ACK is lost",
           {"MIS.G.UP.05"}, client_mutant(_NoLastItemResend))
gcs_mutant("ignores-last-rerequest", "ignores the vehicle's re-request of the last item once it has sent it "
           "(MAVProxy's bug); resends it only at its own timeout", {"MIS.G.UP.04"}, client_mutant(_IgnoresLastRerequest))
gcs_mutant("no-list-resend", "never resends MISSION_REQUEST_LIST (waits out its retries in silence)",
           {"MIS.G.DN.03"}, client_mutant(_NoListResend))
gcs_mutant("no-item-request-resend", "never resends a download's item request",
           {"MIS.G.DN.04"}, client_mutant(_NoItemRequestResend))
gcs_mutant("no-clear-resend", "never resends MISSION_CLEAR_ALL (waits out its retries in silence)",
           {"MIS.G.CL.02"}, client_mutant(_NoClearResend))
gcs_mutant("never-gives-up", "resends to a silent vehicle forever, never ending the operation",
           {"MIS.G.UP.07", "MIS.G.DN.10", "MIS.G.TO.02"}, client_mutant(_NeverGivesUp))
gcs_mutant("short-timeout", "resends after 500 ms and so gives an operation up after 3 s",
           {"MIS.G.TO.01", "MIS.G.TO.03"}, client_mutant(timings=Timings(default_timeout=0.5)))
gcs_mutant("slow-resend", "resends only after 4 s without an answer",
           {"MIS.G.TO.01"}, client_mutant(timings=Timings(default_timeout=4.0)))
gcs_mutant("too-many-retries", "resends one message 8 times before giving up",
           {"MIS.G.TO.02"}, client_mutant(timings=Timings(max_retries=8)))
gcs_mutant("gives-up-early", "retries once only: gives an upload up 3 s after the vehicle went quiet",
           {"MIS.G.TO.03"}, client_mutant(timings=Timings(max_retries=1)))


# --- upload ------------------------------------------------------------------------------------
class _ClearsFirst(MissionClient):
    def upload(self, mission_type, items, now):
        clear = self._to_target(m.clear_all_message(mission_type, self.target))
        return [clear] + super().upload(mission_type, items, now)


def _f32(value: float) -> float:
    return struct.unpack("<f", struct.pack("<f", value))[0]


class _Float32Coordinates(MissionClient):
    def _on_request(self, op, msg, now):
        out = super()._on_request(op, msg, now)
        for action in out:
            if isinstance(action, Send) and action.msg._type == m.ITEM_INT:
                sent = action.msg
                sent.x, sent.y = int(_f32(sent.x / 1e7) * 1e7), int(_f32(sent.y / 1e7) * 1e7)
        return out


class _IntRequestsOnly(MissionClient):
    def handle(self, frame, now):
        if frame.msg._type == m.REQUEST_FLOAT:
            return []
        return super().handle(frame, now)


class _IgnoresUploadNack(MissionClient):
    def _on_ack(self, op, msg, now):
        if op.operation is Operation.UPLOAD and msg.type != MissionResult.ACCEPTED:
            return []
        return super()._on_ack(op, msg, now)


class _Floods(MissionClient):
    def _on_request(self, op, msg, now):
        out = super()._on_request(op, msg, now)
        if msg.seq == 0 and op.answers == 1:   # streams the rest without waiting for requests
            out += [self._to_target(m.item_message(item, self.target)) for item in op.items[1:]]
        return out


class _AnswersTwice(MissionClient):
    def _on_request(self, op, msg, now):
        out = super()._on_request(op, msg, now)
        return out + [a for a in out if isinstance(a, Send) and _is_item(a.msg)]


class _EmptyAsClear(MissionClient):
    def upload(self, mission_type, items, now):
        out = super().upload(mission_type, items, now)
        if items:
            return out
        msg = self._op.last_sent = m.clear_all_message(mission_type, self.target)
        return [self._to_target(msg)]


gcs_mutant("clears-first", "sends MISSION_CLEAR_ALL before every upload's MISSION_COUNT (DroneKit-style)",
           {"MIS.G.UP.01"}, client_mutant(_ClearsFirst))
gcs_mutant("float32-coordinates", "sends MISSION_ITEM_INT x/y through float32 degrees, losing precision",
           {"MIS.G.UP.02"}, client_mutant(_Float32Coordinates))
gcs_mutant("int-requests-only", "ignores MISSION_REQUEST (float form): answers MISSION_REQUEST_INT only",
           {"MIS.G.UP.03"}, client_mutant(_IntRequestsOnly))
gcs_mutant("ignores-upload-nack", "ignores an error MISSION_ACK during an upload and carries on",
           {"MIS.G.UP.08"}, client_mutant(_IgnoresUploadNack))
gcs_mutant("floods-items", "streams every item after the first request instead of waiting for each",
           {"MIS.G.UP.09"}, client_mutant(_Floods))
gcs_mutant("answers-twice", "answers every item request twice (a handler registered twice)",
           {"MIS.G.UP.09"}, client_mutant(_AnswersTwice))
gcs_mutant("empty-as-clear", "uploads an empty plan as MISSION_CLEAR_ALL, not MISSION_COUNT 0",
           {"MIS.G.UP.10"}, client_mutant(_EmptyAsClear))


# --- download ----------------------------------------------------------------------------------
class _ReadsItem0First(MissionClient):
    def download(self, mission_type, now):
        first = m.request_message(0, mission_type, self.target, as_int=self.download_int)
        return [self._to_target(first)] + super().download(mission_type, now)


class _DropsItem0(MissionClient):
    def _finish(self, now, outcome, *, items=None, **rest):
        op = self._op
        if items and op.operation is Operation.DOWNLOAD and op.mission_type is MissionType.MISSION:
            items = tuple(renumber(list(items[1:]), MissionType.MISSION))   # "item 0 is home"
        return super()._finish(now, outcome, items=items, **rest)


def _without_ack(actions: list[Any]) -> list[Any]:
    return [a for a in actions if not (isinstance(a, Send) and a.msg._type == "MISSION_ACK")]


class _NoFinalAck(MissionClient):
    def _on_count(self, op, msg, now):
        return _without_ack(super()._on_count(op, msg, now))

    def _on_item(self, op, msg, now):
        return _without_ack(super()._on_item(op, msg, now))


class _IgnoresCountZero(MissionClient):
    def _on_count(self, op, msg, now):
        if msg.count == 0:
            return []   # waits for items that never come
        return super()._on_count(op, msg, now)


class _TakesOutOfOrderItem(MissionClient):
    def _on_item(self, op, msg, now):
        if msg.seq > op.expected and self.state.name == "DOWNLOAD_REQUESTING":
            msg = _As(msg, seq=op.expected)   # the item that came is taken for the one asked for
        return super()._on_item(op, msg, now)


class _IgnoresDownloadNack(MissionClient):
    def _on_ack(self, op, msg, now):
        if op.operation is Operation.DOWNLOAD and msg.type != MissionResult.ACCEPTED:
            return []
        return super()._on_ack(op, msg, now)


class _IgnoresCancel(MissionClient):
    def _on_ack(self, op, msg, now):
        if msg.type == MissionResult.OPERATION_CANCELLED:
            return []
        return super()._on_ack(op, msg, now)


# DN.06 too: on an empty plan the vehicle NACKs that request, and the GCS takes the NACK
# for the download's end.
gcs_mutant("reads-item-0-first", "requests item 0 (home, it assumes) before a download's MISSION_REQUEST_LIST",
           {"MIS.G.DN.01", "MIS.G.DN.02", "MIS.G.DN.06"}, client_mutant(_ReadsItem0First))
gcs_mutant("drops-item-0", "drops item 0 of a downloaded mission, taking it for the home position",
           {"MIS.G.DN.02", "MIS.G.DN.07"}, client_mutant(_DropsItem0))
gcs_mutant("float-downloads", "requests items with MISSION_REQUEST and keeps the float form's x/y",
           {"MIS.G.DN.09", "MIS.G.DN.02", "MIS.G.DN.07"}, client_mutant(download_int=False))
gcs_mutant("no-final-ack", "sends no MISSION_ACK at the end of a download",
           {"MIS.G.DN.05", "MIS.G.DN.06"}, client_mutant(_NoFinalAck))
gcs_mutant("ignores-count-zero", "ignores MISSION_COUNT 0: never finishes the download of an empty plan",
           {"MIS.G.DN.06"}, client_mutant(_IgnoresCountZero))
gcs_mutant("takes-out-of-order-item", "takes an out-of-sequence item for the one it asked for",
           {"MIS.G.DN.07"}, client_mutant(_TakesOutOfOrderItem))
gcs_mutant("ignores-download-nack", "ignores error MISSION_ACKs during a download and keeps requesting",
           {"MIS.G.DN.08", "MIS.G.CN.01"}, client_mutant(_IgnoresDownloadNack))
gcs_mutant("ignores-cancel", "ignores the vehicle's MISSION_ACK OPERATION_CANCELLED",
           {"MIS.G.CN.01"}, client_mutant(_IgnoresCancel))


# --- plan types --------------------------------------------------------------------------------
class _RequestTypeUnchecked(MissionClient):
    def handle(self, frame, now):
        msg, op = frame.msg, self._op
        if (msg._type in (m.REQUEST_INT, m.REQUEST_FLOAT) and op is not None
                and op.operation is Operation.UPLOAD and msg.mission_type != op.mission_type):
            return self._on_request(op, _As(msg, mission_type=op.mission_type), now)
        return super().handle(frame, now)


class _AckTypeUnchecked(MissionClient):
    def _on_ack(self, op, msg, now):
        if op.operation in (Operation.UPLOAD, Operation.DOWNLOAD):
            msg = _As(msg, mission_type=op.mission_type)
        return super()._on_ack(op, msg, now)


class _ItemTypeUnchecked(MissionClient):
    def _on_item(self, op, msg, now):
        return super()._on_item(op, _As(msg, mission_type=op.mission_type), now)


gcs_mutant("mavlink1", "speaks MAVLink 1 only, so fence and rally messages lose their mission_type",
           {"MIS.G.TY.01"}, client_mutant(mavlink_version=1))
gcs_mutant("request-type-unchecked", "answers an item request of any plan type during an upload",
           {"MIS.G.TY.02"}, client_mutant(_RequestTypeUnchecked))
gcs_mutant("ack-type-unchecked", "takes a MISSION_ACK of any plan type as the running operation's",
           {"MIS.G.TY.03"}, client_mutant(_AckTypeUnchecked))
gcs_mutant("item-type-unchecked", "takes an item of any plan type into the plan being downloaded",
           {"MIS.G.TY.04"}, client_mutant(_ItemTypeUnchecked))


# --- clear -------------------------------------------------------------------------------------
class _ClearsAllTypes(MissionClient):
    def clear(self, mission_type, now):
        super().clear(mission_type, now)
        msg = self._op.last_sent = m.clear_all_message(MissionType.ALL, self.target)
        return [self._to_target(msg)]


class _AnyClearAckIsSuccess(MissionClient):
    def _on_ack(self, op, msg, now):
        if op.operation is Operation.CLEAR and msg.mission_type in (op.clearing, MissionType.ALL):
            return self._finish(now, Outcome.SUCCESS)
        return super()._on_ack(op, msg, now)


gcs_mutant("clears-all-types", "clears the mission with MISSION_CLEAR_ALL of MAV_MISSION_TYPE_ALL",
           {"MIS.G.CL.01"}, client_mutant(_ClearsAllTypes))
gcs_mutant("any-clear-ack-succeeds", "reports a clear done on any MISSION_ACK, an error one too",
           {"MIS.G.CL.03"}, client_mutant(_AnyClearAckIsSuccess))


# the set-current mutants and the addressing ones have modules of their own; importing them
# here registers them with the rest
from . import mutants_current, mutants_routing  # noqa: E402,F401


__all__ = ["GCS_MUTANTS", "GcsMutant", "gcs_mutant", "client_mutant"]
