"""The scripted vehicle: the Mission Protocol's vehicle side, played exactly, with a script.

To judge a GCS the suite must be the vehicle, and a vehicle whose every move it controls:
drop this ACK, ask for an item twice, answer with the wrong mission_type, go silent, send a
NACK. Left alone it answers as seed 000 says (requests with MISSION_REQUEST_INT, ACCEPTED
after the last item, MISSION_COUNT for a list request, an item for each request, ACCEPTED to
a clear, MISSION_CURRENT for a set-current) and never retries on its own: a GCS's obligations
never depend on the vehicle's retries, so a check that wants one scripts it (`rerequest`).

The script is a list of `Rule`s, each used up after `times` firings (None: every time):
`Deaf` (the vehicle does not hear a message), `Swap` (one of its replies is replaced by other
messages, and optionally sent after a delay), `Mute` (it says nothing once a message has
come). Every firing is a note in the log, so the report shows what the vehicle did on purpose.
A swap may also pass on another node's message (`relay`), as a vehicle that routes does.

Sans-IO like every node: `datagram_received`, `poll`, `next_deadline`, `take_outgoing`; it
learns the GCS's address from the first datagram (the GCS speaks first) and only then
starts its HEARTBEAT, unless it is given the address of a GCS that listens (`call`): then it
speaks first, as SITL does to a ground station.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

from mavconform.reference_impl.endpoint import MavlinkEndpoint
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd, CommandResult, MissionResult
from mavconform.reference_impl.mission.items import PLAN_TYPE_BY_VALUE, MissionItem, MissionType
from mavconform.reference_impl.net.node import Address
from mavconform.reference_impl.wire.codec import FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as _d

VEHICLE = (1, 1)
REQUESTS = ("MISSION_REQUEST", "MISSION_REQUEST_INT")
ITEMS = ("MISSION_ITEM", "MISSION_ITEM_INT")
Match = Callable[[Any], bool]


@dataclass
class Event:
    t: float
    dir: str          # "rx": the GCS sent it; "tx": the vehicle sent it; "note": the script acted
    msg: Any          # the message (None for a note)
    version: int = 2  # MAVLink version of a received frame
    text: str = ""    # a note's text

    @property
    def name(self) -> str:
        return self.msg._type if self.msg is not None else self.text


@dataclass
class Rule:
    match: Match
    times: int | None = 1
    what: str = ""          # for the note
    armed_by: Match | None = None   # fires only once the vehicle has heard a message like this

    def hear(self, msg: Any) -> None:
        if self.armed_by is not None and self.armed_by(msg):
            self.armed_by = None

    def fire(self) -> bool:
        if self.times == 0 or self.armed_by is not None:
            return False
        if self.times is not None:
            self.times -= 1
        return True


@dataclass
class Deaf(Rule):
    """The vehicle does not hear a message that matches (as if the link lost it); with
    `rerequest_after`, an item it did not hear is asked for again that much later (its retry)."""
    rerequest_after: float | None = None


@dataclass
class Swap(Rule):
    """A reply that matches is replaced by `instead(reply, vehicle)` (nothing: it is lost),
    and the reply itself is sent `then_after` seconds later if that is set."""
    instead: Callable[[Any, "ScriptedVehicle"], list[Any]] = lambda reply, v: []
    then_after: float | None = None


@dataclass
class Mute(Rule):
    """Once a message that matches has come, the vehicle says nothing more but its HEARTBEAT
    (a busy vehicle, not a lost link)."""


def named(*names: str, **fields: Any) -> Match:
    """A match on the message's name and field values."""
    return lambda msg: msg._type in names and all(getattr(msg, k, None) == v for k, v in fields.items())


@dataclass
class ScriptedVehicle:
    plans: dict[MissionType, list[MissionItem]] = field(default_factory=dict)
    rules: list[Rule] = field(default_factory=list)
    request_float: bool = False          # ask for items with MISSION_REQUEST (the float form)
    wake_every: float | None = None      # s: wake the driver this often (watching a process)
    call: Address | None = None          # a GCS that listens there: the vehicle speaks first


    def __post_init__(self) -> None:
        self.endpoint = MavlinkEndpoint(*VEHICLE, version=2)
        self.log: list[Event] = []
        self.gcs: tuple[int, int] | None = None
        self.muted = False
        self._upload: dict[str, Any] | None = None      # the upload being received
        self._finished: tuple[MissionType, int] | None = None   # the last upload completed
        self._later: list[tuple[float, Any]] = []
        self._relays: dict[tuple[int, int], FrameEncoder] = {}
        self._next_heartbeat: float | None = None
        self._now = 0.0
        if self.call is not None:
            self.endpoint.add_address(self.call)
            self._next_heartbeat = 0.0

    # --- DatagramNode -------------------------------------------------------------------
    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        self._now = now
        for frame in self.endpoint.receive(data, source):
            msg = frame.msg
            if self.gcs is None:
                self.gcs = frame.source
            if self._next_heartbeat is None:
                self._next_heartbeat = now
            if msg._type in ("HEARTBEAT", "BAD_DATA") or not _for_us(msg):
                continue
            self.log.append(Event(now, "rx", msg, frame.version))
            for rule in self.rules:
                rule.hear(msg)
            for rule in self.rules:
                if isinstance(rule, Mute) and not self.muted and rule.match(msg) and rule.fire():
                    self._note(now, f"silent from now on: {rule.what or msg._type}")
                    self.muted = True
            deaf = next((r for r in self.rules if isinstance(r, Deaf) and r.match(msg) and r.fire()), None)
            if deaf is not None:
                self._note(now, f"not heard: {deaf.what or _label(msg)}")
                mt = PLAN_TYPE_BY_VALUE.get(getattr(msg, "mission_type", 0), MissionType.MISSION)
                if deaf.rerequest_after is not None and msg._type in ITEMS:
                    self.later(deaf.rerequest_after, self._request(msg.seq, mt, frame.source))
                continue
            for reply in self._answer(msg, frame.source):
                self.say(reply, now)
        self.poll(now)

    def poll(self, now: float) -> None:
        self._now = now
        due = [msg for t, msg in self._later if t <= now]
        self._later = [(t, msg) for t, msg in self._later if t > now]
        for msg in due:
            self._send(msg, now)
        if self._next_heartbeat is not None and now >= self._next_heartbeat:
            self._next_heartbeat = now + 1.0
            self._send(_d.MAVLink_heartbeat_message(_d.MAV_TYPE_QUADROTOR, _d.MAV_AUTOPILOT_GENERIC,
                                                    0, 0, _d.MAV_STATE_STANDBY, 3), now, log=False)

    def next_deadline(self) -> float | None:
        times = [t for t, _ in self._later]
        if self._next_heartbeat is not None:
            times.append(self._next_heartbeat)
        if self.wake_every is not None:
            times.append(self._now + self.wake_every)
        return min(times) if times else None

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.endpoint.take_outgoing()

    # --- what the script and the checks use ---------------------------------------------
    def say(self, reply: Any, now: float) -> None:
        """Send a reply unless a rule swaps it."""
        swap = next((r for r in self.rules if isinstance(r, Swap) and r.match(reply) and r.fire()), None)
        if swap is None:
            self._send(reply, now)
            return
        self._note(now, f"instead of {_label(reply)}: {swap.what}")
        for msg in swap.instead(reply, self):
            self._send(msg, now)
        if swap.then_after is not None:
            self._later.append((now + swap.then_after, reply))

    def later(self, delay: float, msg: Any) -> None:
        self._later.append((self._now + delay, msg))

    def relay(self, msg: Any, source: tuple[int, int]) -> None:
        """Send `msg` to the GCS as if from `source`, another node on the link (another
        GCS's HEARTBEAT), passed on as a router does: the GCS then knows that node is there."""
        encoder = self._relays.get(source)
        if encoder is None:
            encoder = self._relays[source] = FrameEncoder(*source, version=2)
        self._note(self._now, f"passed on: {_label(msg)} from {source[0]}/{source[1]}")
        self.endpoint.send_raw(encoder.encode(msg), self.gcs)

    @property
    def target(self) -> tuple[int, int]:
        return self.gcs or (255, 0)

    # --- the vehicle side of the protocol -------------------------------------------------
    def _answer(self, msg: Any, peer: tuple[int, int]) -> list[Any]:
        name, to = msg._type, peer
        mt = PLAN_TYPE_BY_VALUE.get(getattr(msg, "mission_type", 0))
        if name == "MISSION_COUNT" and mt is not None:
            self._finished = None
            if msg.count == 0:
                self.plans[mt] = []
                self._upload = None
                return [m.ack_message(MissionResult.ACCEPTED, mt, to)]
            self._upload = {"type": mt, "count": msg.count, "items": []}
            return [self._request(0, mt, to)]
        if name in ITEMS:
            return self._on_item(msg, mt, to)
        if name == "MISSION_REQUEST_LIST" and mt is not None:
            return [m.count_message(len(self.plans.get(mt, [])), mt, to)]
        if name in REQUESTS and mt is not None:
            plan = self.plans.get(mt, [])
            if msg.seq >= len(plan):
                return [m.ack_message(MissionResult.INVALID_SEQUENCE, mt, to)]
            return [m.item_message(plan[msg.seq], to, as_int=name == "MISSION_REQUEST_INT")]
        if name == "MISSION_CLEAR_ALL":
            for t in ([mt] if mt is not None else list(PLAN_TYPE_BY_VALUE.values())):
                self.plans[t] = []
            return [m.ack_message(MissionResult.ACCEPTED, msg.mission_type, to)]
        if name == "MISSION_SET_CURRENT":
            return self._set_current(msg.seq, to, None)
        if name == "COMMAND_LONG" and msg.command == Cmd.DO_SET_MISSION_CURRENT:
            return self._set_current(int(msg.param1), to, msg.command)
        return []

    def _on_item(self, msg: Any, mt: MissionType | None, to: tuple[int, int]) -> list[Any]:
        up = self._upload
        if up is None:
            done = self._finished
            if done is not None and mt is done[0] and msg.seq == done[1] - 1:
                return [m.ack_message(MissionResult.ACCEPTED, mt, to)]   # our ACK was lost: again
            return []
        if mt is not up["type"]:
            return []
        expected = len(up["items"])
        if msg.seq != expected:
            return [self._request(expected, mt, to)]
        item = m.item_from_message(msg)
        up["items"].append(item if item is not None else msg)
        if len(up["items"]) < up["count"]:
            return [self._request(len(up["items"]), mt, to)]
        self.plans[mt] = up["items"]
        self._upload, self._finished = None, (mt, up["count"])
        return [m.ack_message(MissionResult.ACCEPTED, mt, to)]

    def _set_current(self, seq: int, to: tuple[int, int], command: int | None) -> list[Any]:
        total = len(self.plans.get(MissionType.MISSION, []))
        ok = seq < total
        replies = [m.command_ack_message(command, CommandResult.ACCEPTED if ok else CommandResult.DENIED, to)
                   ] if command is not None else []
        if not ok:
            return replies + [m.statustext_message(_d.MAV_SEVERITY_WARNING, f"set current {seq}: not in list")]
        return replies + [m.current_message(seq, total, 0, 0, (0, 0, 0))]

    def _request(self, seq: int, mt: MissionType, to: tuple[int, int]) -> Any:
        return m.request_message(seq, mt, to, as_int=not self.request_float)

    def _send(self, msg: Any, now: float, *, log: bool = True) -> None:
        if self.muted and log:   # silent in the protocol; its HEARTBEAT says it is still there
            return
        if log:
            self.log.append(Event(now, "tx", msg))
        self.endpoint.send(msg, self.gcs)

    def _note(self, now: float, text: str) -> None:
        self.log.append(Event(now, "note", None, text=text))


def _for_us(msg: Any) -> bool:
    """Mission traffic (and commands) addressed to the vehicle, or to everyone."""
    target = getattr(msg, "target_system", None)
    return target in (None, 0, VEHICLE[0])


def _label(msg: Any) -> str:
    seq = getattr(msg, "seq", None)
    return msg._type + (f" {seq}" if seq is not None and msg._type != "HEARTBEAT" else "")

