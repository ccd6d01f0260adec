"""Issue 12: every usage mistake, whoever finds it (argparse or the command), is one stderr
line starting with "mavconform: error: " and exit code 2. argparse's lines name the
subcommand after the prefix; the commands' own lines name the option or file."""

from __future__ import annotations

import subprocess
import sys

import pytest

from mavconform.cli import main
from mavconform.reference_impl.files import SAMPLES_DIR

ERROR_PREFIX = "mavconform: error: "   # the one form of a usage mistake, for people and scripts

PLAN = str(SAMPLES_DIR / "demo.plan")
NOWHERE = "udp:no-such-host.invalid:14550"

BAD = [
    # (argv, what the line says); FILES/ is replaced by a folder of bad files
    ([], "the following arguments are required: COMMAND"),
    (["frobnicate"], "invalid choice: 'frobnicate'"),
    (["run", "--bogus"], "unrecognized arguments: --bogus"),
    (["run", "--time-scale", "abc"], "run: argument --time-scale: 'abc' is not a number"),
    (["run", "--level", "X"], "--level: unknown level 'X'"),
    (["run", "--target", "udpin:[::1]"], "bad endpoint 'udpin:[::1]': missing port"),
    (["run", "--target", NOWHERE], "cannot resolve host 'no-such-host.invalid'"),
    (["run", "--expect", "nosuchautopilot"], "--expect 'nosuchautopilot'"),
    (["run", "--baseline", "FILES/bad.json"], "FILES/bad.json"),
    (["fuzz", "--mode", "bits"], "fuzz: argument --mode: invalid choice: 'bits'"),
    (["fuzz", "--time", "0"], "fuzz: argument --time: bad duration '0'"),
    (["fuzz", "--target", "http:127.0.0.1:5"], "unknown scheme 'http'"),
    (["fuzz", "--capture", "x.mcap"], "--capture goes with --replay"),
    (["fuzz", "--replay", "FILES/missing.json"], "FILES/missing.json"),
    (["gcs"], "gcs: the following arguments are required: OPERATION"),
    (["gcs", "upload", PLAN], "gcs upload: the following arguments are required: --target"),
    (["gcs", "clear", "--target", "udp:127.0.0.1:5", "--type", "bogus"], "gcs clear: argument --type"),
    (["gcs", "set-current", "--target", "udp:127.0.0.1:5", "70000"], "gcs set-current: argument SEQ"),
    (["gcs", "upload", "--target", "udp:127.0.0.1", PLAN], "--target: bad endpoint 'udp:127.0.0.1': missing port"),
    (["gcs", "upload", "--target", NOWHERE, PLAN], "--target: bad endpoint"),
    (["gcs", "upload", "--target", "udp:127.0.0.1:5", "FILES/bad.plan"], "FILES/bad.plan"),
    (["gcs", "download", "--target", "udp:127.0.0.1:5", "FILES/nodir/back.plan"], "does not exist"),
    (["vehicle", "--loss", "1.5"], "vehicle: argument --loss: '1.5' is not a probability"),
    (["vehicle", "--listen", "udp:127.0.0.1:99999"], "--listen: bad endpoint 'udp:127.0.0.1:99999': bad port"),
    (["vehicle", "--listen", "udpin:0", "--connect", "udpin:5"], "--connect: bad endpoint 'udpin:5'"),
    (["vehicle", "--listen", "udpin:0", "--profile", "FILES/bad.toml"], "FILES/bad.toml"),
    (["vehicle", "--listen", "udpin:0", "--mutant", "nope"], "--mutant: unknown mutant 'nope'"),
    (["proxy", "--listen", "udpin:0"], "proxy: the following arguments are required: --forward"),
    (["proxy", "--listen", "udpin:0", "--forward", "udp:127.0.0.1:9", "--max-gcs", "0"], "proxy: argument --max-gcs"),
    (["proxy", "--listen", "udpin:0", "--forward", "udpin:14550"], "--forward: bad endpoint 'udpin:14550'"),
    (["proxy", "--listen", "tcp:127.0.0.1:0", "--forward", "udp:127.0.0.1:9"], "--listen: bad endpoint"),
    (["clauses", "--level", "X"], "--level: unknown level 'X'"),
    (["clauses", "--output", "x.md"], "--output: only with --coverage"),
    (["clauses", "--json", "--bogus"], "unrecognized arguments: --bogus"),
    (["report", "bogus"], "report: argument ACTION: invalid choice: 'bogus'"),
    (["report", "render"], "report render: the following arguments are required: RUN.json"),
    (["report", "render", "FILES/bad.json"], "FILES/bad.json"),
    (["report", "render", "FILES/missing.json"], "FILES/missing.json: cannot read"),
    (["report", "expectations", "FILES/bad.json"], "FILES/bad.json"),
    (["profiles", "--show", "nope"], "profile 'nope'"),
    (["demo", "--plan", "FILES/bad.plan"], "FILES/bad.plan"),
    (["fault-table", "--output", "FILES/nodir/x.md"], "no such directory"),
]


@pytest.fixture
def files(tmp_path):
    (tmp_path / "bad.json").write_text("{not json")
    (tmp_path / "bad.plan").write_text('{"fileType": "Plan", "version": 1, "mission": '
                                       '{"version": 2, "items": [{"type": "ComplexItem"}]}}')
    (tmp_path / "bad.toml").write_text('base = "px4"\nwarp = 1\n')
    return tmp_path


def _argv(argv: list[str], files, tmp_path) -> list[str]:
    argv = [a.replace("FILES", str(files)) for a in argv]
    if argv[:1] == ["run"]:
        argv += ["--report-dir", str(tmp_path / "reports")]
    if argv[:1] == ["fuzz"]:
        argv += ["--report-dir", str(tmp_path / "reports"), "--findings", str(tmp_path / "findings"),
                 "--database", "none"]
    if argv[:1] in (["vehicle"], ["proxy"]):
        argv += ["--duration", "0.1"]   # should one be accepted after all, it stops at once
    return argv


@pytest.mark.parametrize("argv, says", BAD, ids=[" ".join(a).replace(PLAN, "demo.plan")[:60] or "(none)"
                                                  for a, _ in BAD])
def test_every_usage_mistake_is_one_prefixed_line_and_exit_2(argv, says, files, tmp_path, capsys):
    try:
        code = main(_argv(argv, files, tmp_path))
    except SystemExit as exc:   # argparse's mistakes
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith(ERROR_PREFIX), err
    assert says.replace("FILES", str(files)) in err, err


@pytest.mark.parametrize("argv", [
    ["gcs", "upload", PLAN],                                 # argparse, in a nested subcommand
    ["vehicle", "--listen", "udpin:[::1]", "--duration", "0.1"],   # the command's own check
])
def test_the_installed_command_prints_the_same_one_line(argv):
    done = subprocess.run([sys.executable, "-m", "mavconform", *argv], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.count("\n") == 1 and done.stderr.startswith(ERROR_PREFIX), done.stderr


@pytest.mark.udp
def test_a_silent_target_is_a_finding_not_an_error(capsys):
    """exit 1 and "mavconform: target unresponsive: ...", as `run` says it; "error:" is kept
    for the user's mistakes."""
    assert main(["gcs", "clear", "--target", "udp:127.0.0.1:9", "--heartbeat-timeout", "0.2"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("mavconform: target unresponsive: udp:127.0.0.1:9: no HEARTBEAT"), err
    assert "error" not in err
