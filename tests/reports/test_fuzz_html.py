"""fuzz.html: the finding's exchange on the lanes its peers name, with its times, and a
capture link that works from the folder the page is written in."""

import os
import re
from pathlib import Path
from urllib.parse import unquote

from mavconform.reports.html import html_report
from mavconform.reports.run_document import check_run
from mavconform.reports.write import write_reports

from .sample import clause, event, run_document

# What a fuzz finding's replay should carry: the fuzzer's GCS as "tester", a second GCS,
# the vehicle implicit (tx: to it, rx: from it), the replay's own times.
EXCHANGE = [event(0.0, "tx", "MISSION_COUNT", count=2, mission_type=2),
            event(0.0012, "rx", "MISSION_REQUEST_INT", seq=0, mission_type=2),
            event(0.0031, "tx", "MISSION_COUNT", peer="gcs-b", count=1, mission_type=2),
            event(0.0042, "rx", "MISSION_ACK", peer="gcs-b", type=15, mission_type=2),
            event(0.25, "rx", "MISSION_ACK", type=10, mission_type=2)]


def fuzz_document(capture):
    doc = run_document()
    row = clause("FUZZ.PROTOCOL.atomic-upload", "fail", [], gating=True,
                 detail="atomic-upload after step 0: the vehicle stores 1 items as its rally plan")
    row.pop("duration_s")
    row["exchange"] = [{k: v for k, v in e.items() if k != "t"} for e in EXCHANGE]
    doc["clauses"] = [row]
    doc["volatile"]["clauses"] = {row["id"]: {"duration_s": 0.0,
                                              "events": [e["t"] for e in EXCHANGE]}}
    doc["identity"] = None
    doc["gating"].update(mode="default", regressions=[], fixed=[])
    doc["summary"] = {"total": 1, "pass": 0, "fail": 1, "known-deviation": 0,
                      "not-applicable": 0, "skipped": 0, "error": 0, "gating_failures": 1,
                      "verdict": "fail"}
    doc["capture"] = capture
    doc["fuzz"] = {"mode": "protocol", "examples": 10, "units": 20, "findings": []}
    return check_run(doc)


def diagram(text):
    return re.search(r'<svg class="sequence".*?</svg>', text, re.S).group(0)


def capture_href(text):
    return unquote(re.search(r'<tr><th>capture</th><td><a href="([^"]+)">', text).group(1))


def test_the_lanes_are_the_peers_of_the_exchange_and_the_times_are_real():
    svg = diagram(html_report(fuzz_document(None)))
    lanes = re.findall(r'<text class="actor[^"]*" x="[\d.]+" y="22">([^<]*)</text>', svg)
    assert lanes == ["tester", "vehicle (target)", "gcs-b"]
    times = re.findall(r'<text class="time(?: decided-mark)?" [^>]*>([^<]*)</text>', svg)
    assert times == ["+0.000 s", "+0.001 s", "+0.003 s", "+0.004 s", "▶ +0.250 s"]
    assert "type=15 (MAV_MISSION_OPERATION_CANCELLED)" in svg


def test_the_capture_link_works_from_the_report_folder_with_findings_elsewhere(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "found").mkdir()
    mcap = tmp_path / "found" / "protocol-atomic-upload-1 x.mcap"
    mcap.write_bytes(b"\x89MCAP0\r\n")
    for capture in ("found/protocol-atomic-upload-1 x.mcap", str(mcap)):   # as --findings gave it
        paths = write_reports(fuzz_document(capture), "rep/deeper", basename="fuzz")
        text = paths["html"].read_text(encoding="utf-8")
        href = capture_href(text)
        assert not os.path.isabs(href)
        assert (paths["html"].parent / href).resolve() == mcap.resolve()
        assert f">{capture}</a>" in text   # shown as the campaign named it


def test_a_capture_inside_the_report_folder_stays_a_bare_name(tmp_path, doc):
    (tmp_path / "run 1.mcap").write_bytes(b"")
    text = write_reports(doc, tmp_path)["html"].read_text(encoding="utf-8")
    assert capture_href(text) == "run 1.mcap"
    assert html_report(doc, folder=Path("elsewhere")).count('href="run%201.mcap"') == 1
