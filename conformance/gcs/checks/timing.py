"""The timing clauses (MIS.G.TO.*): the spec's 1500 ms and 5 retries, with MIS.UP.07's tolerance."""

from __future__ import annotations

import statistics

from ...harness.measured import Measured
from ...outcome import ClauseFailed
from ..harness import GcsHarness
from ..scripted_vehicle import ITEMS, Mute, named
from . import check
from .common import (ACCEPTED_TIMEOUT, DEFAULT_TIMEOUT, KEPT_OPEN, MAX_RETRIES, fail, mission_sent,
                     silent_to_count, upload_job)


@check("MIS.G.TO.01")
def resend_timeout(h: GcsHarness) -> str:
    op = silent_to_count(h)
    counts = op.sent("MISSION_COUNT")
    if len(counts) < 2:
        raise fail(h, op, counts[0], "MISSION_COUNT was never resent: the GCS has no resend timeout "
                                     f"({op.result.line()})")
    gaps = [b.t - a.t for a, b in zip(counts, counts[1:])]
    median = statistics.median(gaps)
    low, high = ACCEPTED_TIMEOUT
    h.decide(op, counts[1])
    text = Measured(f"MISSION_COUNT resent every <ms> ms (median of {len(gaps)}); expected about "
                    f"{DEFAULT_TIMEOUT * 1000:.0f} ms (accepted: {low * 1000:.0f}-{high * 1000:.0f} ms)",
                    ms=f"{median * 1000:.0f}")
    if not low <= median <= high:
        raise ClauseFailed(text)
    return text


@check("MIS.G.TO.02")
def retry_limit(h: GcsHarness) -> str:
    op = silent_to_count(h)
    counts = op.sent("MISSION_COUNT")
    resends = len(counts) - 1
    h.decide(op, counts[-1])
    if resends > MAX_RETRIES:
        raise ClauseFailed(f"MISSION_COUNT was resent {resends} times"
                           + ("" if op.result.ended else " and the GCS was still sending when stopped")
                           + f"; expected at most {MAX_RETRIES}")
    return f"MISSION_COUNT resent {resends} times (at most {MAX_RETRIES})"


@check("MIS.G.TO.03")
def kept_open(h: GcsHarness) -> str:
    op = h.run(upload_job(), rules=[Mute(named(*ITEMS, seq=0), what="after item 0")])
    told = op.told()
    last = told[-1] if told else op.sent()[0]
    if not op.result.ended:
        h.decide(op, last)
        return f"the upload was still open when stopped after {h.timeout_s:g} s"
    open_for = op.result.at - last.t
    h.decide(op, (mission_sent(op) or op.sent())[-1])
    text = Measured(f"the GCS gave the upload up <s> s after the vehicle's last message; the spec's timeouts "
                    f"and retries keep it open {DEFAULT_TIMEOUT * (MAX_RETRIES + 1):g} s (accepted: from "
                    f"{KEPT_OPEN:g} s)", s=f"{open_for:.1f}")
    if open_for < KEPT_OPEN:
        raise ClauseFailed(text)
    return text
