"""What our sockets' receive queues dropped: volatile.receive_queue, and every view says it."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from mavconform.reports.html import html_report
from mavconform.reports.junit import junit_xml
from mavconform.reports.markdown import markdown_summary
from mavconform.reports.run_document import check_run, receive_queue
from mavconform.reports.text import dropped_text

MIB8 = 8 * 1024 * 1024


@pytest.mark.parametrize("dropped, said", [
    (0, "none dropped (receive buffer 8192 KiB)"),
    (1, "1 datagram dropped before we read them (receive buffer 8192 KiB)"),
    (1234, "1234 datagrams dropped before we read them (receive buffer 8192 KiB)"),
    (None, "drops unknown (this platform does not count them) (receive buffer 8192 KiB)"),
])
def test_the_drops_are_said_as_counted_or_unknown(doc, dropped, said):
    doc["volatile"]["receive_queue"] = {"dropped": dropped, "buffer_bytes": MIB8}
    check_run(doc)
    assert dropped_text(doc) == said
    assert f"Our sockets' receive queues: {said}." in markdown_summary(doc)
    assert f"<th>our receive queues</th><td>{said}</td>" in html_report(doc)
    properties = {p.get("name"): p.get("value") for p in ET.fromstring(junit_xml(doc)).iter("property")}
    assert properties["volatile.receive_queue.dropped"] == ("null" if dropped is None else str(dropped))
    assert properties["volatile.receive_queue.buffer_bytes"] == str(MIB8)


def test_a_run_that_did_not_record_them_shows_nothing_about_them(doc):
    assert receive_queue(doc) is None and dropped_text(doc) is None
    assert "receive queue" not in markdown_summary(doc) and "receive queue" not in html_report(doc)
    assert not any("receive_queue" in (p.get("name") or "")
                   for p in ET.fromstring(junit_xml(doc)).iter("property"))


def test_an_unknown_buffer_is_left_out(doc):
    doc["volatile"]["receive_queue"] = {"dropped": 0, "buffer_bytes": None}   # virtual time: no socket
    check_run(doc)
    assert dropped_text(doc) == "none dropped"
