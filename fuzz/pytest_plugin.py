"""Fuzz campaigns as pytest tests, so pytest-xdist spreads them over cores:

    pytest --pyargs mavconform.fuzz -n auto --fuzz-target builtin:spec --fuzz-shards 8 --fuzz-examples 500

Registered as a pytest11 entry point; it only adds options until `--fuzz-target` is given.
Each test is one shard of a campaign: a mode and a shard number, whose seed is derived from
`--fuzz-seed` and the shard, so shards explore different examples. A shard's finding is saved
as a case that replays exactly; the examples a shard explores can differ with the example
database and, in a worker that already ran other shards, with what Hypothesis kept from them
(fuzz/seeded.py). All shards share one Hypothesis example database (`--fuzz-database`, a
directory by default; Hypothesis's directory database is safe for concurrent processes), so
an example one worker found is tried first by every later run. For machines that do not
share a disk, `--fuzz-database redis://HOST:PORT` shares it through Redis.
A shard with a finding fails, naming the broken invariant and the saved case to replay.
A usage mistake is pytest's usage error (exit 4), one line naming the option.
"""

from __future__ import annotations

from typing import Any

import pytest


def pytest_addoption(parser: pytest.Parser) -> None:
    g = parser.getgroup("mavconform-fuzz", "MAVLink mission fuzz campaigns (mavconform)")
    g.addoption("--fuzz-target", metavar="URI",
                help="fuzz URI (builtin:PROFILE: spec, px4, ardupilot, ... (`mavconform profiles`); mutant:NAME, "
                     "udp:HOST:PORT, udpin:[HOST:]PORT, tcp:HOST:PORT, tcpin:[HOST:]PORT or serial:DEVICE[:BAUD])")
    g.addoption("--fuzz-mode", default="protocol,frames", metavar="MODES",
                help="comma-separated modes (default protocol,frames)")
    g.addoption("--fuzz-shards", type=int, default=2, metavar="N", help="shards per mode (default 2)")
    g.addoption("--fuzz-examples", type=int, default=100, metavar="N", help="examples per shard (default 100)")
    g.addoption("--fuzz-time", metavar="DURATION", help="wall-time budget per shard, e.g. 5m")
    g.addoption("--fuzz-seed", type=int, default=0, help="fleet seed (default 0)")
    g.addoption("--fuzz-findings", default="fuzz-findings", metavar="DIR", help="where findings are saved")
    g.addoption("--fuzz-database", default=".hypothesis/fuzz", metavar="DIR|none|redis://HOST:PORT",
                help="shared Hypothesis example database (default .hypothesis/fuzz)")


def _settings(config: pytest.Config) -> dict[str, Any]:
    from mavconform.fuzz.campaign import MODES, parse_duration
    from mavconform.reference_impl.errors import UsageError

    modes = [m.strip() for m in config.getoption("--fuzz-mode").split(",") if m.strip()]
    bad = [m for m in modes if m not in MODES]
    if bad or not modes:
        raise pytest.UsageError(f"--fuzz-mode: unknown mode(s) {', '.join(bad) or '(none)'} "
                                f"(expected {', '.join(MODES)})")
    shards, examples = config.getoption("--fuzz-shards"), config.getoption("--fuzz-examples")
    if shards < 1 or examples < 1:
        raise pytest.UsageError("--fuzz-shards and --fuzz-examples must be at least 1")
    from mavconform.conformance.target_uri import parse_target
    from mavconform.fuzz_cmd import open_database

    def checked(option: str, parse: Any) -> Any:
        try:
            return parse(config.getoption(option))
        except UsageError as exc:
            raise pytest.UsageError(f"{option}: {exc}") from None

    checked("--fuzz-target", parse_target)
    time_s = checked("--fuzz-time", lambda text: parse_duration(text) if text else None)
    try:
        open_database(config.getoption("--fuzz-database"))
    except UsageError as exc:   # its message names the option (as the CLI spells it)
        raise pytest.UsageError(str(exc)) from None
    return {"modes": modes, "shards": shards, "examples": examples, "time_s": time_s}


def pytest_configure(config: pytest.Config) -> None:
    if config.getoption("--fuzz-target", default=None):
        _settings(config)   # a mistake is a usage error before anything runs


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "fuzz_shard" not in metafunc.fixturenames:
        return
    if not metafunc.config.getoption("--fuzz-target"):
        metafunc.parametrize("fuzz_shard", [pytest.param(None, marks=pytest.mark.skip(
            reason="no --fuzz-target given"))], ids=["no-target"])
        return
    s = _settings(metafunc.config)
    shards = [(mode, i) for mode in s["modes"] for i in range(s["shards"])]
    metafunc.parametrize("fuzz_shard", shards, ids=[f"{m}-{i}" for m, i in shards])


def run_shard(config: pytest.Config, mode: str, shard: int) -> None:
    from mavconform.fuzz.campaign import CampaignOptions, run_campaign
    from mavconform.fuzz.report import replay_command
    from mavconform.fuzz_cmd import open_database
    from mavconform.reference_impl.errors import UsageError
    from mavconform.reference_impl.net.sim import stable_seed

    s = _settings(config)
    seed = stable_seed(config.getoption("--fuzz-seed"), mode, shard) & 0x7FFFFFFF
    try:
        options = CampaignOptions(
            target=config.getoption("--fuzz-target"), mode=mode, seed=seed,
            examples=s["examples"], time_s=s["time_s"], findings_dir=config.getoption("--fuzz-findings"),
            database=open_database(config.getoption("--fuzz-database")))
        result = run_campaign(options)
    except UsageError as exc:
        raise pytest.UsageError(str(exc)) from None
    if result.findings:
        pytest.fail("\n".join(f"{f.case.violation}\n  replay: {replay_command(f)}"
                              for f in result.findings), pytrace=False)
