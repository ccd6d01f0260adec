"""Message authenticity for handover: the roster of known GCSs and the gate in front of control.

The handover design (DESIGN.md, Handover) carries control over MAVLink "authenticated with
MAVLink 2 signing", and the thesis (seed 003) passes every message "through a security layer
to ensure authenticity before executing" it. This module is that layer's policy; the
checking itself is the codec's (wire/codec.py, over pymavlink):

- A `Roster` names the GCSs the vehicle knows: system id, its own 32-byte key (and the link
  id the vehicle writes when signing to it), a name for logs. `Roster.keyring` is what the
  endpoint checks frames by: each frame against the key of the system id it claims, so GCS B
  signing with B's key while writing A's system id fails ("bad signature"), a system with no
  key fails ("unknown key"), and a genuine frame played again fails ("replayed": its
  timestamp is not newer than the last one of its (system, component, link id) stream, or
  it opens a new stream more than a minute behind the vehicle's clock).
- Which key signs what: each GCS signs with its own key; the vehicle signs what it sends to
  a GCS with that GCS's key (MAVLink keys are shared by the two ends of a link). So a GCS
  needs only its own key, and none can forge what the vehicle tells another GCS.
- `UnknownGcsGate` sits in front of the control manager: a system id outside the roster
  (and not the vehicle's own) never reaches it, so it can never be granted control, even
  when the vehicle accepts unsigned frames. Its request is answered COMMAND_ACK DENIED
  (asking again cannot work); its other state-changing messages are refused as a GCS not in
  control is refused, even while control is open to all (`open_when_unowned`); reads pass.
- Nothing here reads a clock; what is refused is counted, and a refusal carries its answer.
  A frame the signature check drops gets no answer at all (it is counted in the endpoint's
  `rejections` and kept in `rejected`): answering would tell an injector what works and
  make the vehicle a reflector for forged traffic.

Limits, as the signing scheme has them: replay state lives in memory, so after a vehicle
restart only the one-minute rule stands against replays; and signing authenticates frames,
not addresses, so a recorded frame that reaches the vehicle before its genuine copy is taken
as the genuine one (its content is the GCS's own, but replies then go to where it came from).

A roster file is JSON, a list of entries (see `load_roster`).
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import UsageError
from ..mission.actions import Send
from ..wire.frame import Frame
from ..wire.signing import Keyring, SigningKey, secret_from_hex, secret_from_passphrase
from ..wire.dialect import mavlink as _d
from . import control_messages as cm
from .control_manager import refuse_state_change
from .control_results import Refusal


@dataclass(frozen=True)
class KnownGcs:
    """One roster entry: a GCS's system id, its signing key, and a name for logs."""

    sysid: int
    key: SigningKey            # key.link_id: the link id the vehicle signs frames to it with
    name: str = ""

    def __post_init__(self) -> None:
        if not 1 <= self.sysid <= 255:
            raise ValueError(f"a GCS system id is 1..255, got {self.sysid}")

    @property
    def label(self) -> str:
        return f"{self.name} ({self.sysid})" if self.name else f"GCS {self.sysid}"


@dataclass(frozen=True)
class Roster:
    """The GCSs a vehicle knows, each with its own key. Hashable (a VehicleConfig field)."""

    gcss: tuple[KnownGcs, ...]

    def __post_init__(self) -> None:
        seen: set[int] = set()
        for g in self.gcss:
            if g.sysid in seen:
                raise ValueError(f"system {g.sysid} is in the roster twice")
            seen.add(g.sysid)

    @property
    def sysids(self) -> frozenset[int]:
        return frozenset(g.sysid for g in self.gcss)

    def knows(self, sysid: int) -> bool:
        return any(g.sysid == sysid for g in self.gcss)

    def keyring(self, own_system: int | None = None, own_key: SigningKey | None = None) -> Keyring:
        """The keys frames are checked by: every GCS's, plus the vehicle's own for its own
        system id (a companion computer sharing the vehicle's key), if it has one."""
        if own_system is not None and self.knows(own_system):
            raise ValueError(f"system {own_system} is the vehicle's own, not a GCS")
        own = [(own_system, own_key)] if own_system is not None and own_key is not None else []
        return Keyring([(g.sysid, g.key) for g in self.gcss] + own)


class UnknownGcsGate:
    """Keeps systems outside the roster away from operator control (sans-IO, no clock).

    The vehicle calls `screen(frame)` before its control manager hears a frame: a refusal
    (with what to answer) or None to go on. The vehicle's own system id always passes
    (its components are never filtered)."""

    def __init__(self, roster: Roster, system: int, component: int) -> None:
        self.known = roster.sysids | {system}
        self.system, self.component = system, component
        self.refused: Counter[int] = Counter()   # refused frames by unknown system id

    def screen(self, frame: Frame) -> Refusal | None:
        src, msg = frame.source, frame.msg
        if src[0] in self.known:
            return None
        who = f"system {src[0]} is not in the roster"
        name = msg._type
        refusal: Refusal | None
        if cm.is_request_control(msg) and cm.addressed_to(msg, self.system, self.component):
            ack = cm.command_ack(msg.command, _d.MAV_RESULT_DENIED, src)
            refusal = Refusal(f"{name} {msg.command}: {who}", (Send(ack, src),))
        elif name == "COMMAND_ACK" and msg.command == cm.REQUEST_CONTROL:
            refusal = Refusal(f"{name}: {who}", ())   # an answer to a forward it never got
        elif cm.addressed_to(msg, self.system, self.component):
            # what a GCS not in control is refused, whatever the real manager's settings
            refusal = refuse_state_change(msg, src, who, _d.MAV_RESULT_NOT_IN_CONTROL, "not in control")
        else:
            refusal = None
        if refusal is not None:
            self.refused[src[0]] += 1
        return refusal


# --- roster files ----------------------------------------------------------------------------
ENTRY_FIELDS = ("sysid", "key", "passphrase", "link_id", "name")


def load_roster(path: str | Path) -> Roster:
    """A roster from a JSON file: a list of entries such as

        [{"sysid": 201, "name": "GCS A", "key": "<64 hex digits>"},
         {"sysid": 202, "name": "GCS B", "passphrase": "words only B knows", "link_id": 1}]

    `key` (the 32 bytes in hex) or `passphrase` (SHA-256 of its ASCII bytes, as MAVProxy's
    `signing setup` makes keys), not both; `link_id` (0..255, default 0) is what the vehicle
    writes into the signatures of frames to that GCS. A mistake raises a `UsageError` naming
    the file and the entry."""
    where = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise UsageError(f"{where}: roster file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"{where}: cannot read the roster: {exc}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise UsageError(f"{where}:{exc.lineno}:{exc.colno}: not JSON: {exc.msg}") from None
    return roster_from_json(data, where)


def roster_from_json(data: Any, where: str = "roster") -> Roster:
    """A roster from parsed JSON (see `load_roster`); `where` names the source in errors."""
    if not isinstance(data, list):
        raise UsageError(f"{where}: a roster is a JSON list of entries "
                         '([{"sysid": 201, "key": "<64 hex digits>", "name": "GCS A"}, ...])')
    if not data:
        raise UsageError(f"{where}: the roster is empty: no GCS could ever be heard")
    entries: list[KnownGcs] = []
    first_at: dict[int, int] = {}
    for i, item in enumerate(data, 1):
        entry = _entry(item, f"{where}: entry {i}")
        if entry.sysid in first_at:
            raise UsageError(f"{where}: entry {i}: sysid {entry.sysid} is already entry {first_at[entry.sysid]}")
        first_at[entry.sysid] = i
        entries.append(entry)
    return Roster(tuple(entries))


def _entry(item: Any, where: str) -> KnownGcs:
    if not isinstance(item, dict):
        raise UsageError(f"{where}: an entry is an object with \"sysid\" and \"key\" or \"passphrase\"")
    name = item.get("name", "")
    if not isinstance(name, str):
        raise UsageError(f"{where}: \"name\" must be a string")
    if name:
        where = f"{where} ({name!r})"
    unknown = sorted(set(item) - set(ENTRY_FIELDS))
    if unknown:
        raise UsageError(f"{where}: unknown field {unknown[0]!r} (fields: {', '.join(ENTRY_FIELDS)})")
    sysid = _whole(item, "sysid", 1, 255, where, required=True)
    link_id = _whole(item, "link_id", 0, 255, where, required=False)
    if ("key" in item) == ("passphrase" in item):
        raise UsageError(f"{where}: give \"key\" (64 hex digits) or \"passphrase\", exactly one")
    field = "key" if "key" in item else "passphrase"
    value = item[field]
    if not isinstance(value, str):
        raise UsageError(f"{where}: \"{field}\" must be a string")
    try:
        secret = secret_from_hex(value) if field == "key" else secret_from_passphrase(value)
    except ValueError as exc:
        raise UsageError(f"{where}: \"{field}\": {exc}") from None
    return KnownGcs(sysid, SigningKey(secret, link_id), name)


def _whole(item: dict, field: str, low: int, high: int, where: str, *, required: bool) -> int:
    if field not in item:
        if required:
            raise UsageError(f"{where}: \"{field}\" is missing")
        return 0
    value = item[field]
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise UsageError(f"{where}: \"{field}\" must be a whole number in {low}..{high}, got {json.dumps(value)}")
    return value
