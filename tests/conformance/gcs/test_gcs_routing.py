"""The addressing clauses (MIS.G.RT.*) and the set-current resend (MIS.G.SC.03), in virtual time:
what the scripted vehicle puts on the link, each path of the checks, and the command form of
set-current. The negative controls (test_gcs_negative_controls.py) show each clause failing on
its mutant and passing on the reference GCS.
"""

from __future__ import annotations

from mavconform.conformance.gcs.adapters import NodeAdapter
from mavconform.conformance.gcs.checks.routing import _misaddressed, other_component, other_system
from mavconform.conformance.gcs.clauses import GCS_CLAUSES
from mavconform.conformance.gcs.harness import GcsHarness
from mavconform.conformance.gcs.mutants import GCS_MUTANTS, client_mutant
from mavconform.conformance.gcs.runner import run_gcs_clauses
from mavconform.conformance.gcs.scripted_vehicle import VEHICLE, ScriptedVehicle
from mavconform.conformance.outcome import ClauseResult, Outcome
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.wire.codec import FrameDecoder

NEW = ("MIS.G.RT.01", "MIS.G.RT.02", "MIS.G.RT.03", "MIS.G.SC.03")


def _run(adapter: NodeAdapter, ids: tuple[str, ...] = NEW) -> tuple[GcsHarness, dict[str, ClauseResult]]:
    h = GcsHarness(adapter, real_time=False, timeout_s=30)
    results = run_gcs_clauses(h, [c for c in GCS_CLAUSES if c.id in ids]).results
    return h, {r.clause_id: r for r in results}


def test_other_addresses_are_never_the_gcs_the_vehicle_or_broadcast() -> None:
    for gcs in [(255, 190), (245, 190), (2, 1), (3, 255), (1, 2)]:
        for other in (other_system(gcs), other_component(gcs)):
            assert other != gcs and 0 not in other and other != VEHICLE, (gcs, other)
        assert other_system(gcs)[1] == gcs[1] and other_component(gcs)[0] == gcs[0]


def test_a_relayed_heartbeat_comes_from_the_other_node() -> None:
    v = ScriptedVehicle()
    v.gcs = (255, 190)
    v.endpoint.add_address(("127.0.0.1", 2))
    v.relay(m.gcs_heartbeat_message(), (255, 191))
    frames = [f for data, _ in v.take_outgoing() for f in FrameDecoder().feed(data)]
    assert [(f.msg._type, f.src_system, f.src_component) for f in frames] == [("HEARTBEAT", 255, 191)]
    assert v.log[-1].text == "passed on: HEARTBEAT from 255/191"


def test_the_reference_gcs_ignores_the_acks_to_others_in_upload_and_clear() -> None:
    h, results = _run(NodeAdapter(), ("MIS.G.RT.01", "MIS.G.RT.02"))
    assert all(r.outcome is Outcome.PASS for r in results.values()), results
    ops = h.operations
    assert [op.job.op for op in ops] == ["upload", "clear", "upload", "clear"]
    for op, other in zip(ops, [other_system, other_system, other_component, other_component]):
        decoy, real = op.told("MISSION_ACK")
        assert (decoy.msg.target_system, decoy.msg.target_component) == other(op.gcs)
        assert decoy.msg.type == MissionResult.DENIED and real.msg.type == MissionResult.ACCEPTED
        assert (real.msg.target_system, real.msg.target_component) == op.gcs
        assert op.result.ok and op.result.at >= real.t
    # only the component's decoy comes with that component's HEARTBEAT passed on first
    assert [any(e.text.startswith("passed on: HEARTBEAT") for e in op.events) for op in ops] == [
        False, False, True, True]


class _TakesClearAcksToAnyone(MissionClient):
    """Takes any MISSION_ACK during a clear (an upload it gets right)."""

    def _addressed_to_us(self, msg):
        return msg._type == "MISSION_ACK" and self.busy and self._op.clearing is not None \
            or super()._addressed_to_us(msg)


def test_a_gcs_wrong_in_its_clear_only_fails_too() -> None:
    _, results = _run(NodeAdapter("clear only", build=client_mutant(_TakesClearAcksToAnyone)),
                      ("MIS.G.RT.01", "MIS.G.RT.02"))
    for r in results.values():
        assert r.outcome is Outcome.FAIL and r.detail.startswith("the clear failed after MISSION_ACK DENIED"), r


def test_the_set_current_command_may_go_to_component_0_but_mission_messages_may_not() -> None:
    command = m.set_current_command(2, (VEHICLE[0], 0))
    assert _misaddressed(command) is None
    assert "went to 2/1" in _misaddressed(m.set_current_command(2, (2, 1)))
    assert _misaddressed(m.set_current_message(2, VEHICLE)) is None
    assert "MISSION_SET_CURRENT 2 went to 1/0" in _misaddressed(m.set_current_message(2, (VEHICLE[0], 0)))
    assert "went to 0/1" in _misaddressed(m.count_message(3, MissionType.MISSION, (0, VEHICLE[1])))


class _SetsCurrentByCommand(MissionClient):
    def set_current(self, seq, now, *, via_command=False):
        return super().set_current(seq, now, via_command=True)


def test_set_current_by_command_is_resent_and_judged_alike() -> None:
    h, results = _run(NodeAdapter("by command", build=client_mutant(_SetsCurrentByCommand)), ("MIS.G.SC.03",))
    assert results["MIS.G.SC.03"].outcome is Outcome.PASS, results
    sent = h.operations[0].sent("COMMAND_LONG")
    assert len(sent) == 2 and sent[1].t - sent[0].t == 1.5
    assert any(e.text == "not heard: the first set-current" for e in h.operations[0].events)


def test_the_mutants_fail_with_what_they_did() -> None:
    expected = {
        "ack-to-any-system": ("MIS.G.RT.01", "the upload failed after MISSION_ACK DENIED addressed to 254/190"),
        "ack-to-any-component": ("MIS.G.RT.02", "the upload failed after MISSION_ACK DENIED addressed to 255/191"),
        "broadcast-component": ("MIS.G.RT.03", "MISSION_COUNT went to 1/0, not to the vehicle's 1/1"),
        "no-set-current-resend": ("MIS.G.SC.03", "MISSION_SET_CURRENT was sent 1 time(s)"),
    }
    for name, (clause, detail) in expected.items():
        _, results = _run(NodeAdapter(name, build=GCS_MUTANTS[name].build), (clause,))
        assert results[clause].outcome is Outcome.FAIL and results[clause].detail.startswith(detail), (
            name, results[clause].detail)


class _NeverHearsClearAcks(MissionClient):
    def _addressed_to_us(self, msg):
        return not (msg._type == "MISSION_ACK" and self.busy and self._op.clearing is not None) \
            and super()._addressed_to_us(msg)


def test_a_gcs_that_fails_every_clear_is_not_blamed_on_the_ack_to_another() -> None:
    _, results = _run(NodeAdapter("deaf clears", build=client_mutant(_NeverHearsClearAcks)), ("MIS.G.RT.01",))
    r = results["MIS.G.RT.01"]
    assert r.outcome is Outcome.ERROR and "so does one with no ACK to another GCS" in r.detail, r
