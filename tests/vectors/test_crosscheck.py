"""The vectors through two implementations that are not ours (tools/vectors_crosscheck.py):
the MAVLink C library mavgen generates from the dialect XML, compiled here with gcc, and
gomavlib (Go) with its own development dialect, built from the Go module proxy. A missing
toolchain FAILS with the reason: the cross-check is never skipped silently."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from mavconform.vectors import deviations, store, verify
from mavconform.vectors.dialect_info import load_dialect

from .helpers import load_crosscheck

vc = load_crosscheck()


def _outcome(implementation: str, vectors: list, dialect, work: Path):
    try:
        return vc.crosscheck(implementation, vectors, dialect, store.load(store.DATA_DIR).index["test_key"]["hex"],
                             work)
    except vc.ToolchainMissing as exc:
        pytest.fail(f"{implementation} cross-check cannot run: {exc}")


@pytest.mark.parametrize("implementation", vc.IMPLEMENTATIONS)
def test_every_vector_agrees_but_the_known_deviations(implementation: str, committed, dialect, tmp_path: Path) -> None:
    outcome = _outcome(implementation, committed.messages, dialect, tmp_path)
    assert outcome.lacks == []      # gomavlib's development dialect has every message and field of ours
    report = verify.check(implementation, committed.messages, outcome.results, dialect)
    sorted_ = deviations.sort(report, deviations.load())
    assert [str(m) for m in sorted_.unexpected] == []
    assert sorted_.unused == []
    assert report.checked == len(committed.messages) == len(outcome.results)


def test_the_c_library_made_from_a_users_dialect_agrees_too(added_xml: Path, tmp_path: Path) -> None:
    user = load_dialect(added_xml)
    store.generate(tmp_path / "v", user)
    vectors = store.load(tmp_path / "v").messages
    outcome = _outcome("c", vectors, user, tmp_path / "c")
    sorted_ = deviations.sort(verify.check("c", vectors, outcome.results, user), deviations.load())
    assert [str(m) for m in sorted_.unexpected] == []
    assert any(v["message"] == "VECTORS_TEST_ADDED" and outcome.results[v["id"]]["ok"] for v in vectors)


def test_gomavlib_says_precisely_what_its_dialect_lacks(added_xml: Path, tmp_path: Path) -> None:
    user = load_dialect(added_xml)
    built = vc.build_go(tmp_path)
    assert vc.go_lacks(built.exe, user) == [
        "VECTORS_TEST_ADDED (id 600): no such message in gomavlib's development dialect"]


def test_a_missing_toolchain_is_a_failure_with_the_reason(monkeypatch, dialect, tmp_path: Path) -> None:
    monkeypatch.setattr(shutil, "which", lambda name: None)
    monkeypatch.setattr(vc, "GO_FALLBACK", tmp_path / "no-go")
    with pytest.raises(vc.ToolchainMissing, match="no C compiler"):
        vc.build_c(dialect, tmp_path)
    with pytest.raises(vc.ToolchainMissing, match="no Go toolchain"):
        vc.build_go(tmp_path)
    assert vc.main(["--impl", "c", "--work", str(tmp_path / "w")]) == 1
