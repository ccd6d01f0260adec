"""Signing rosters: the file format, its mistakes, and the command line that takes one
(`vehicle --signing-roster`, `gcs control --signing-key`), down to a vehicle process."""

from __future__ import annotations

import json

import pytest

from mavconform.cli import main
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover.authenticity import KnownGcs, load_roster, roster_from_json
from mavconform.reference_impl.wire.signing import SigningKey

from .gcs_keys import A, B, KEY_A, KEY_X, STRANGER, key

HEX_A = KEY_A.secret.hex()


def test_roster_from_json_reads_keys_and_passphrases():
    roster = roster_from_json([{"sysid": A, "key": HEX_A, "name": "A", "link_id": 1},
                               {"sysid": B, "passphrase": "B"}])
    assert roster.gcss == (KnownGcs(A, SigningKey(KEY_A.secret, 1), "A"), KnownGcs(B, SigningKey(key("B", 0).secret)))
    assert roster.knows(B) and not roster.knows(STRANGER) and roster.sysids == {A, B}
    ring = roster.keyring(1, KEY_X)
    assert ring.key_for(A).secret == KEY_A.secret and ring.key_for(1) == KEY_X and STRANGER not in ring
    with pytest.raises(ValueError, match="vehicle's own"):
        roster.keyring(A)


@pytest.mark.parametrize("data, message", [
    ({"sysid": A}, "a JSON list of entries"),
    ([], "the roster is empty"),
    (["x"], "entry 1: an entry is an object"),
    ([{"key": HEX_A}], 'entry 1: "sysid" is missing'),
    ([{"sysid": 0, "key": HEX_A}], 'entry 1: "sysid" must be a whole number in 1..255, got 0'),
    ([{"sysid": "201", "key": HEX_A}], '"sysid" must be a whole number in 1..255, got "201"'),
    ([{"sysid": A, "key": HEX_A[:-2], "name": "A"}], "entry 1 ('A'): \"key\": a signing key is 64 hex digits, got 62"),
    ([{"sysid": A, "key": HEX_A}, {"sysid": B}], 'entry 2: give "key" (64 hex digits) or "passphrase", exactly one'),
    ([{"sysid": A, "key": HEX_A, "passphrase": "x"}], "exactly one"),
    ([{"sysid": A, "passphrase": "pässword"}], '"passphrase": the passphrase must be ASCII'),
    ([{"sysid": A, "key": HEX_A, "link_id": 256}], '"link_id" must be a whole number in 0..255'),
    ([{"sysid": A, "key": HEX_A, "keys": 1}], "unknown field 'keys'"),
    ([{"sysid": A, "key": HEX_A}, {"sysid": A, "passphrase": "x"}], "entry 2: sysid 201 is already entry 1"),
])
def test_roster_mistakes_name_the_file_and_the_entry(data, message):
    with pytest.raises(UsageError) as err:
        roster_from_json(data, "gcss.json")
    assert str(err.value).startswith("gcss.json: ") and message in str(err.value), str(err.value)
    assert "\n" not in str(err.value)


def test_roster_file_errors(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('[{"sysid": 201,\n "key": }]')
    with pytest.raises(UsageError, match=r"bad\.json:2:9: not JSON"):
        load_roster(bad)
    with pytest.raises(UsageError, match="roster file not found"):
        load_roster(tmp_path / "missing.json")
    good = tmp_path / "good.json"
    good.write_text(json.dumps([{"sysid": A, "key": HEX_A}]))
    assert load_roster(good).knows(A)


def test_cli_usage_errors_are_one_line_and_exit_2(tmp_path, capsys):
    roster = tmp_path / "gcss.json"
    roster.write_text(json.dumps([{"sysid": 1, "key": HEX_A, "name": "self"}]))
    assert main(["vehicle", "--signing-roster", str(roster)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{roster}: entry 1: sysid 1 is the vehicle's own" in err
    roster.write_text("[]")
    assert main(["vehicle", "--signing-roster", str(roster)]) == 2
    assert "the roster is empty" in capsys.readouterr().err
    assert main(["vehicle", "--accept-unsigned"]) == 2
    assert "--accept-unsigned needs --signing-roster" in capsys.readouterr().err
    target = ["--target", "udp:127.0.0.1:9"]
    with pytest.raises(SystemExit) as exit_:
        main(["gcs", "control", "request", *target, "--signing-key", "12ab"])
    assert exit_.value.code == 2 and "64 hex digits, got 4" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["gcs", "control", "request", *target, "--signing-key", HEX_A, "--signing-passphrase", "x"])
    assert "not allowed with argument" in capsys.readouterr().err
    assert main(["gcs", "control", "request", *target, "--signing-link-id", "3"]) == 2
    assert "--signing-link-id needs --signing-key" in capsys.readouterr().err


@pytest.mark.udp
def test_signed_gcs_takes_control_of_a_vehicle_process_and_an_unsigned_one_is_not_heard(tmp_path, capsys):
    """`mavconform vehicle --signing-roster`: GCS 201 with its key is heard and granted
    control; GCS 202 without its key is dropped, so the vehicle never even answers it; the
    vehicle prints what it dropped."""
    from ..vehicle_process import vehicle_process

    roster = tmp_path / "gcss.json"
    roster.write_text(json.dumps([{"sysid": A, "name": "A", "key": HEX_A}, {"sysid": B, "passphrase": "B"}]))
    with vehicle_process("--operator-control", "--owner-loss", "60", "--signing-roster", str(roster)) as port:
        target = ["--target", f"udp:127.0.0.1:{port}"]
        assert main(["gcs", "control", "request", *target, "--system", str(A), "--signing-key", HEX_A]) == 0
        assert "ok   request control: granted" in capsys.readouterr().out
        assert main(["gcs", "clear", *target, "--system", str(B), "--heartbeat-timeout", "1.5"]) == 1
        assert "target unresponsive" in capsys.readouterr().err
        assert main(["gcs", "clear", *target, "--system", str(B), "--signing-passphrase", "B"]) == 1
        assert "DENIED" in capsys.readouterr().out        # heard now, but A is in control
