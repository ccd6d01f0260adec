"""Collected by `pytest --pyargs mavconform.conformance --mavlink-target URI` (see pytest_plugin.py)."""

from __future__ import annotations


def test_clause(mavlink_session, mavlink_clause, request) -> None:
    from mavconform.conformance.pytest_plugin import _prepared, decide
    p = _prepared(request.config)
    decide(mavlink_session, mavlink_clause, p.expected, p.options.strict)
