"""MIS.CAN.04 and MIS.UP.08 resend an unanswered MISSION_COUNT once, as a spec GCS does.

Seen on INAV 9.1 SITL over TCP: now and then the MISSION_COUNT that opens a new upload after
a quiet spell drew no answer at all (CAN.04 in one run of five, UP.08 in one of four), and
the clause failed on a lost message it does not judge (conformance/harness/procedures.py
`send_count`).
"""

from __future__ import annotations

from mavconform.conformance.catalogue import CLAUSES
from mavconform.conformance.mutants import MUTANTS, Mutant, server_mutant
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.server import MissionServer


class _IgnoresCountsAfterCancel(MissionServer):
    """After a GCS cancels an upload, ignores the next `ignored` MISSION_COUNTs."""

    ignored = 1

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._to_ignore = 0

    def _on_ack(self, msg, src, now):
        if msg.type == MissionResult.OPERATION_CANCELLED:
            self._to_ignore = self.ignored
        return super()._on_ack(msg, src, now)

    def _on_count(self, msg, src, now):
        if self._to_ignore:
            self._to_ignore -= 1
            return []
        return super()._on_count(msg, src, now)


class _NeverAnswersCountsAfterCancel(_IgnoresCountsAfterCancel):
    ignored = 1000


def _judge(monkeypatch, server_cls: type[MissionServer], clause_id: str = "MIS.CAN.04"):
    """One clause against a vehicle whose mission server is `server_cls`."""
    monkeypatch.setitem(MUTANTS, "test-only", Mutant("test-only", "", frozenset(), server_mutant(server_cls)))
    with Session(parse_target("mutant:test-only"), virtual=True) as session:
        return run_clauses(session, [c for c in CLAUSES if c.id == clause_id]).results[0]


def test_a_count_answered_at_once_is_not_resent():
    with Session(parse_target("builtin:spec"), virtual=True) as session:
        result = run_clauses(session, [c for c in CLAUSES if c.id == "MIS.CAN.04"]).results[0]
    assert result.outcome is Outcome.PASS, result.detail
    assert not any("resends it once" in str(e.get("msg", "")) for e in result.exchange), result.exchange


def test_a_count_lost_once_is_resent_and_the_clause_judged(monkeypatch):
    result = _judge(monkeypatch, _IgnoresCountsAfterCancel)
    assert result.outcome is Outcome.PASS, result.detail
    assert any("resends it once" in str(e.get("msg", "")) for e in result.exchange), result.exchange


def test_a_count_never_answered_still_fails(monkeypatch):
    result = _judge(monkeypatch, _NeverAnswersCountsAfterCancel)
    assert result.outcome is Outcome.FAIL and "expected MISSION_REQUEST" in result.detail


class _IgnoresTheFirstCountOfTwo(MissionServer):
    """Drops the first MISSION_COUNT of 2 items it gets (MIS.UP.08's fresh upload)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._dropped = False

    def _on_count(self, msg, src, now):
        if msg.count == 2 and not self._dropped:
            self._dropped = True
            return []
        return super()._on_count(msg, src, now)


def test_the_fresh_upload_after_a_given_up_one_resends_an_unanswered_count(monkeypatch):
    """Seen on INAV 9.1 SITL in MIS.UP.08 (round 9): the same drop as MIS.CAN.04's."""
    result = _judge(monkeypatch, _IgnoresTheFirstCountOfTwo, "MIS.UP.08")
    assert result.outcome is Outcome.PASS, result.detail
    assert any("resends it once" in str(e.get("msg", "")) for e in result.exchange)
