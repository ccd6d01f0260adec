"""The GCS-side engine under a hand-played vehicle: the helpers test_client*.py share."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.items import MissionType as T

from .script import GCS, VEHICLE, Script


def client(**kw) -> Script:
    return Script(MissionClient(*GCS, VEHICLE, **kw))


def req(seq, t=T.MISSION, as_int=True):
    return m.request_message(seq, t, GCS, as_int=as_int)


def vack(result, t=T.MISSION, opaque_id=0):
    return m.ack_message(result, t, GCS, opaque_id)


def result(s: Script):
    assert len(s.results) == 1, s.results
    return s.results[0]


def download_reply(items, seq, as_int=True):
    return m.item_message(items[seq], GCS, as_int=as_int)
