"""Collected by `pytest --pyargs fuzz --fuzz-target URI` (see pytest_plugin.py)."""

from __future__ import annotations


def test_campaign_shard(fuzz_shard, request) -> None:
    from fuzz.pytest_plugin import run_shard
    mode, shard = fuzz_shard
    run_shard(request.config, mode, shard)
