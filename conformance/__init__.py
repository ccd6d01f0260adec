"""Clause registry and conformance runner (see the conformance issue)."""
