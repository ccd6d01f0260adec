"""Transition tables of the mission engines: state -> event -> new state, as data.

The engines move only through these tables (an unlisted move raises), so the table is the
truth a test can walk and a report can draw (after h11's `_state.py`).
"""

from __future__ import annotations

from ..state_table import TableEnum


class SlotState(TableEnum):
    """A vehicle-side transfer slot (one per plan type)."""

    IDLE = "idle"
    RECEIVING = "receiving"   # upload: requesting items from the GCS
    SENDING = "sending"       # download: answering the GCS's requests


class SlotEvent(TableEnum):
    COUNT = "MISSION_COUNT > 0 accepted"
    COUNT_ZERO = "MISSION_COUNT = 0 (clear)"
    COUNT_REJECTED = "MISSION_COUNT refused (NO_SPACE)"
    ITEM_NEXT = "expected item, more to come"
    ITEM_LAST = "expected last item: commit"
    ITEM_OUT_OF_SEQUENCE = "item out of sequence: dropped (a gap is re-requested)"
    ITEM_REJECTED = "item refused by validation"
    REQUEST_LIST = "MISSION_REQUEST_LIST, plan not empty"
    REQUEST_LIST_EMPTY = "MISSION_REQUEST_LIST, plan empty"
    REQUEST_VALID = "request for an existing item"
    REQUEST_INVALID = "request beyond the plan (INVALID_SEQUENCE)"
    ACK = "MISSION_ACK from the partner"
    CLEAR = "MISSION_CLEAR_ALL"
    STRAY = "item or request outside any transfer"
    TIMEOUT_RETRY = "timeout: resend"
    TIMEOUT_GIVE_UP = "timeout: retries exhausted"
    CANCEL = "cancelled by the vehicle"
    SUPERSEDED = "partner started another operation"
    # reached only with a profile's knobs (PROFILE_TRANSITIONS)
    PARTIAL_WRITE = "MISSION_WRITE_PARTIAL_LIST accepted"
    ITEM_REFUSED_GOES_ON = "item refused with an error ACK, the upload goes on"
    FORM_FLIPPED = "MISSION_ACK UNSUPPORTED: request form flipped (int/float)"
    REQUEST_LIST_UNTRACKED = "MISSION_REQUEST_LIST answered, no download state kept"
    REQUEST_UNTRACKED = "request answered outside any download"


_S, _E = SlotState, SlotEvent
SERVER_TRANSITIONS: dict[tuple[SlotState, SlotEvent], SlotState] = {
    (_S.IDLE, _E.COUNT): _S.RECEIVING,
    (_S.IDLE, _E.COUNT_ZERO): _S.IDLE,
    (_S.IDLE, _E.COUNT_REJECTED): _S.IDLE,
    (_S.IDLE, _E.REQUEST_LIST): _S.SENDING,
    (_S.IDLE, _E.REQUEST_LIST_EMPTY): _S.IDLE,
    (_S.IDLE, _E.CLEAR): _S.IDLE,
    (_S.IDLE, _E.STRAY): _S.IDLE,
    (_S.RECEIVING, _E.ITEM_NEXT): _S.RECEIVING,
    (_S.RECEIVING, _E.ITEM_LAST): _S.IDLE,
    (_S.RECEIVING, _E.ITEM_OUT_OF_SEQUENCE): _S.RECEIVING,
    (_S.RECEIVING, _E.ITEM_REJECTED): _S.IDLE,
    (_S.RECEIVING, _E.TIMEOUT_RETRY): _S.RECEIVING,
    (_S.RECEIVING, _E.TIMEOUT_GIVE_UP): _S.IDLE,
    (_S.RECEIVING, _E.ACK): _S.IDLE,
    (_S.RECEIVING, _E.CANCEL): _S.IDLE,
    (_S.RECEIVING, _E.SUPERSEDED): _S.IDLE,
    (_S.SENDING, _E.REQUEST_VALID): _S.SENDING,
    (_S.SENDING, _E.REQUEST_INVALID): _S.IDLE,
    (_S.SENDING, _E.ACK): _S.IDLE,
    (_S.SENDING, _E.TIMEOUT_GIVE_UP): _S.IDLE,
    (_S.SENDING, _E.CANCEL): _S.IDLE,
    (_S.SENDING, _E.SUPERSEDED): _S.IDLE,
}

# Moves only a profile's knobs make (non-spec behaviour: VARIANTS.md A3, A9, A14, P8). Kept
# apart so the spec table stays exactly what the spec vehicle walks.
PROFILE_TRANSITIONS: dict[tuple[SlotState, SlotEvent], SlotState] = {
    (_S.IDLE, _E.PARTIAL_WRITE): _S.RECEIVING,
    (_S.RECEIVING, _E.ITEM_REFUSED_GOES_ON): _S.RECEIVING,
    (_S.RECEIVING, _E.FORM_FLIPPED): _S.RECEIVING,
    (_S.IDLE, _E.REQUEST_LIST_UNTRACKED): _S.IDLE,
    (_S.IDLE, _E.REQUEST_UNTRACKED): _S.IDLE,
}
ALL_SERVER_TRANSITIONS = {**SERVER_TRANSITIONS, **PROFILE_TRANSITIONS}


class ClientState(TableEnum):
    """The GCS-side engine (one operation at a time)."""

    IDLE = "idle"
    UPLOAD_COUNT_SENT = "upload: MISSION_COUNT sent"
    UPLOAD_SENDING = "upload: answering requests"
    DOWNLOAD_LIST_SENT = "download: MISSION_REQUEST_LIST sent"
    DOWNLOAD_REQUESTING = "download: requesting items"
    CLEAR_SENT = "clear: MISSION_CLEAR_ALL sent"
    SET_CURRENT_SENT = "set current: waiting for MISSION_CURRENT"


class ClientEvent(TableEnum):
    START_UPLOAD = "upload started: MISSION_COUNT sent"
    START_DOWNLOAD = "download started: MISSION_REQUEST_LIST sent"
    START_CLEAR = "clear started: MISSION_CLEAR_ALL sent"
    START_SET_CURRENT = "set current started"
    REQUEST = "vehicle requested an item"
    COUNT = "vehicle sent MISSION_COUNT"
    ITEM = "expected item received"
    ITEM_OUT_OF_SEQUENCE = "item out of sequence: dropped (a gap is re-requested)"
    CLEAR_NEXT = "plan type cleared: MISSION_CLEAR_ALL for the next type sent"
    RESTART = "download ended by a vehicle error: MISSION_REQUEST_LIST sent again"
    TIMEOUT_RETRY = "timeout: resend"
    FINISH = "operation finished (success, NACK, timeout, cancel or protocol error)"


_C, _V = ClientState, ClientEvent
CLIENT_TRANSITIONS: dict[tuple[ClientState, ClientEvent], ClientState] = {
    (_C.IDLE, _V.START_UPLOAD): _C.UPLOAD_COUNT_SENT,
    (_C.IDLE, _V.START_DOWNLOAD): _C.DOWNLOAD_LIST_SENT,
    (_C.IDLE, _V.START_CLEAR): _C.CLEAR_SENT,
    (_C.IDLE, _V.START_SET_CURRENT): _C.SET_CURRENT_SENT,
    (_C.UPLOAD_COUNT_SENT, _V.REQUEST): _C.UPLOAD_SENDING,
    (_C.UPLOAD_COUNT_SENT, _V.TIMEOUT_RETRY): _C.UPLOAD_COUNT_SENT,
    (_C.UPLOAD_COUNT_SENT, _V.FINISH): _C.IDLE,
    (_C.UPLOAD_SENDING, _V.REQUEST): _C.UPLOAD_SENDING,
    (_C.UPLOAD_SENDING, _V.TIMEOUT_RETRY): _C.UPLOAD_SENDING,
    (_C.UPLOAD_SENDING, _V.FINISH): _C.IDLE,
    (_C.DOWNLOAD_LIST_SENT, _V.COUNT): _C.DOWNLOAD_REQUESTING,
    (_C.DOWNLOAD_LIST_SENT, _V.TIMEOUT_RETRY): _C.DOWNLOAD_LIST_SENT,
    (_C.DOWNLOAD_LIST_SENT, _V.FINISH): _C.IDLE,
    (_C.DOWNLOAD_REQUESTING, _V.ITEM): _C.DOWNLOAD_REQUESTING,
    (_C.DOWNLOAD_REQUESTING, _V.ITEM_OUT_OF_SEQUENCE): _C.DOWNLOAD_REQUESTING,
    (_C.DOWNLOAD_REQUESTING, _V.TIMEOUT_RETRY): _C.DOWNLOAD_REQUESTING,
    (_C.DOWNLOAD_REQUESTING, _V.FINISH): _C.IDLE,
    (_C.DOWNLOAD_REQUESTING, _V.RESTART): _C.DOWNLOAD_LIST_SENT,
    (_C.DOWNLOAD_LIST_SENT, _V.RESTART): _C.DOWNLOAD_LIST_SENT,
    (_C.CLEAR_SENT, _V.TIMEOUT_RETRY): _C.CLEAR_SENT,
    (_C.CLEAR_SENT, _V.CLEAR_NEXT): _C.CLEAR_SENT,
    (_C.CLEAR_SENT, _V.FINISH): _C.IDLE,
    (_C.SET_CURRENT_SENT, _V.TIMEOUT_RETRY): _C.SET_CURRENT_SENT,
    (_C.SET_CURRENT_SENT, _V.FINISH): _C.IDLE,
}
