"""Collected by `pytest --pyargs mavconform.fuzz --fuzz-target URI` (see pytest_plugin.py)."""

from __future__ import annotations


def test_campaign_shard(fuzz_shard, request) -> None:
    from mavconform.fuzz.pytest_plugin import run_shard
    mode, shard = fuzz_shard
    run_shard(request.config, mode, shard)
