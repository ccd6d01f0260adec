"""The clause catalogue: ids, checks, and that every quoted sentence is where it says."""

from __future__ import annotations

from pathlib import Path

import pytest

from mavconform.conformance import catalogue
from mavconform.conformance.checks import CHECKS
from mavconform.conformance.clause import Clause, Level, Role
from mavconform.conformance.gcs.checks import GCS_CHECKS
from mavconform.reference_impl.errors import UsageError

SHARED = Path(__file__).resolve().parents[3] / "shared"


def test_every_clause_has_exactly_one_check_and_every_check_a_clause() -> None:
    ids = {c.id for c in catalogue.CLAUSES}
    assert ids == set(CHECKS), (sorted(ids - set(CHECKS)), sorted(set(CHECKS) - ids))


def test_every_gcs_clause_has_exactly_one_check_and_every_gcs_check_a_clause() -> None:
    ids = {c.id for c in catalogue.GCS_CLAUSES}
    assert ids == set(GCS_CHECKS), (sorted(ids - set(GCS_CHECKS)), sorted(set(GCS_CHECKS) - ids))


def test_ids_are_unique_well_formed_and_grouped() -> None:
    assert len(catalogue.BY_ID) == len(catalogue.CLAUSES) + len(catalogue.GCS_CLAUSES) + len(catalogue.MSP_CLAUSES)
    assert 40 <= len(catalogue.CLAUSES) <= 90
    assert all(c.role is Role.VEHICLE for c in catalogue.CLAUSES)
    assert all(c.role is Role.GCS and c.id.startswith("MIS.G.") for c in catalogue.GCS_CLAUSES)
    assert catalogue.BY_ID["MIS.G.UP.01"].group == "G.UP" and catalogue.BY_ID["MIS.UP.01"].group == "UP"
    with pytest.raises(ValueError):
        Clause("UP.1", Level.MUST, Role.VEHICLE, "t", "s", "r")


@pytest.mark.skipif(not SHARED.is_dir(), reason="../shared (the seed texts) is not beside the project")
@pytest.mark.parametrize("clause", catalogue.CLAUSES + catalogue.GCS_CLAUSES, ids=lambda c: c.id)
def test_requirement_is_quoted_from_the_cited_line(clause: Clause) -> None:
    path, _, line = clause.source.rpartition(":")
    lines = (SHARED / path).read_text(encoding="utf-8").splitlines()
    # the sentence starts on the cited line (the XML wraps descriptions: allow 3 lines)
    window = " ".join(lines[int(line) - 1:int(line) + 2])
    words = clause.requirement.split()
    probe = " ".join(words[-6:]) if "MAV_MISSION" in words[0] else " ".join(words[:6])
    assert probe.rstrip(":") in " ".join(window.split()), (clause.id, probe, window[:200])


def test_select_by_glob_and_level() -> None:
    assert [c.id for c in catalogue.select("mis.up.0[1-3]")] == ["MIS.UP.01", "MIS.UP.02", "MIS.UP.03"]
    assert all(c.level is Level.MAY for c in catalogue.select(None, "may"))
    assert len(catalogue.select("MIS.UP.01, MIS.CLR.*")) == 1 + len(catalogue.select("MIS.CLR.*"))


def test_select_keeps_the_roles_apart() -> None:
    assert all(c.role is Role.VEHICLE for c in catalogue.select("MIS.*"))
    assert [c.id for c in catalogue.select("mis.g.up.0[12]", role=Role.GCS)] == ["MIS.G.UP.01", "MIS.G.UP.02"]
    with pytest.raises(UsageError, match="matches no gcs clause"):
        catalogue.select("MIS.UP.01", role=Role.GCS)


@pytest.mark.parametrize("globs,levels,message", [
    ("MIS.ZZ.*", None, "matches no vehicle clause"),
    (" , ", None, "no pattern"),
    (None, "MUSTNT", "unknown level"),
])
def test_select_rejects_mistakes(globs, levels, message) -> None:
    with pytest.raises(UsageError, match=message):
        catalogue.select(globs, levels)
