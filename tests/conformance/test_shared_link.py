"""Several GCS identities on one link (root cause 1 of the real-target verdicts).

A real SITL's GCS link is bound to one peer address (VARIANTS.md L1, L2): a second GCS on a
socket of its own is never heard, and replies meant for it arrive on the first GCS's
socket. The builtin px4 and ardupilot profiles model that link, so these tests fail if the
suite ever goes back to one socket per GCS for such a target.
"""

from __future__ import annotations

import pytest

from mavconform.conformance.catalogue import BY_ID
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target

SECOND_GCS_CLAUSES = ("MIS.GCS.01", "MIS.DN.07", "MIS.CAN.03", "MIS.ERR.02")


def _outcomes(target: str, *, shared_link: bool | None, udp: bool = False) -> dict[str, Outcome]:
    with Session(parse_target(target), virtual=not udp, shared_link=shared_link) as session:
        run = run_clauses(session, [BY_ID[c] for c in SECOND_GCS_CLAUSES], restore=False)
        return {r.clause_id: r.outcome for r in run.results}


@pytest.mark.parametrize("profile", ["px4", "ardupilot"])
def test_a_single_peer_target_never_hears_a_second_socket(profile: str) -> None:
    got = _outcomes(f"builtin:{profile}", shared_link=False)
    assert all(o is not Outcome.PASS for o in got.values()), got


@pytest.mark.parametrize("profile", ["px4", "ardupilot"])
def test_by_default_the_second_gcs_shares_the_link_of_a_single_peer_target(profile: str) -> None:
    got = _outcomes(f"builtin:{profile}", shared_link=None)
    assert got["MIS.DN.07"] is Outcome.PASS and got["MIS.CAN.03"] is Outcome.PASS, got


@pytest.mark.udp
def test_the_shared_link_works_over_real_udp() -> None:
    got = _outcomes("builtin:px4", shared_link=None, udp=True)
    assert got["MIS.DN.07"] is Outcome.PASS and got["MIS.CAN.03"] is Outcome.PASS, got


def test_external_targets_share_the_link_and_spec_keeps_separate_sockets() -> None:
    with Session(parse_target("builtin:spec"), virtual=True) as spec:
        assert spec.shared_link is False
    with Session(parse_target("udpin:0")) as external:
        assert external.shared_link is True
