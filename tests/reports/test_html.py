import re
from html.parser import HTMLParser

from mavconform.reports.deciding import deciding_event
from mavconform.reports.html import html_report
from mavconform.reports.run_document import clause_detail, clause_events
from mavconform.reports.sequence_svg import MAX_EVENTS, sequence_diagram

from .sample import FAILED_ARROWS, UPLOAD_OK, event

VOID = {"meta", "input", "br", "hr", "img", "link"}
SVG_EMPTY = {"line", "rect", "polygon"}  # written self-closed


class Structure(HTMLParser):
    """Every element seen, and whether each one that was opened was closed in order."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.tags, self.text = [], [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def handle_endtag(self, tag):
        assert self.stack and self.stack[-1] == tag, (tag, self.stack[-5:])
        self.stack.pop()

    def handle_data(self, data):
        self.text.append(data)


def structure(text):
    parser = Structure()
    parser.feed(text)
    parser.close()
    assert parser.stack == []
    return parser


def sections(text):
    """{clause id: the HTML of its finding section}."""
    return dict(re.findall(r'<section class="clause" id="clause-([^"]+)">(.*?)</section>',
                           text, re.S))


def test_page_is_balanced_self_contained_and_script_free(doc):
    text = html_report(doc)
    assert text.startswith("<!DOCTYPE html>")
    parsed = structure(text)
    tags = [tag for tag, _ in parsed.tags]
    assert "script" not in tags and "<script" not in text
    assert "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt;" in text
    # the hostile text is still there for a reader, as text
    assert '<script>alert("x")</script>' in "".join(parsed.text)
    assert not any(ch in text for ch in "\x00\x07\x1b\u202e\ud800")
    # no external assets: the only links are the capture and fragments
    hrefs = [attrs["href"] for tag, attrs in parsed.tags if "href" in attrs]
    assert all(h.startswith("#") or h == "run%201.mcap" for h in hrefs), hrefs
    assert not any("src" in attrs for _, attrs in parsed.tags)
    assert "http://" not in text.replace('xmlns="http://www.w3.org/2000/svg"', "")


def test_header_counts_and_matrix(doc):
    text = html_report(doc)
    assert '<p class="verdict fail">❌ FAIL' in text
    assert "<code>udp:127.0.0.1:14550 &lt;b&gt;|</code>" in text
    assert "<td>system 1 component 1, type 2, autopilot 4, MAVLink 2</td>" in text
    assert "<tr><th>address</th><td>127.0.0.1:40001</td></tr>" in text
    assert "<tr><th>started</th><td>2026-11-22T10:00:00Z</td></tr>" in text
    assert "<tr><th>duration</th><td>12.5 s</td></tr>" in text
    assert "<tr><th>forced waits</th><td>9.100 s</td></tr>" in text
    assert '<a href="run%201.mcap">run 1.mcap</a>' in text
    assert '<td><span class="badge o-fail">fail</span></td><td class="n">1</td>' in text
    matrix = text[text.index('<table class="matrix">'):]
    matrix = matrix[:matrix.index("</table>")]
    assert re.findall(r'<tr class="group"><th colspan="4">(\w+) \((\d)\)', matrix) == [
        ("UP", "2"), ("DL", "1"), ("FENCE", "1"), ("CLR", "1"), ("CUR", "1")]
    assert re.findall(r'<tr class="o-([\w-]+)"><td class="id"><a href="#clause-([\w.]+)"',
                      matrix) == [(c["outcome"], c["id"]) for c in doc["clauses"]]


def test_a_section_with_a_diagram_for_each_clause_not_passing(doc):
    text = html_report(doc)
    found = sections(text)
    assert list(found) == ["MIS.UP.07", "MIS.CUR.04", "MIS.DL.02", "MIS.FENCE.01", "MIS.CLR.03"]
    for clause in doc["clauses"][1:]:
        body = found[clause["id"]]
        assert body.count("<svg") == 1
        drawn = [e for e in clause["exchange"] if e["dir"] != "note"]
        assert body.count('<g class="arrow') == len(drawn)
        assert "“The vehicle responds with MISSION_REQUEST_INT for each item.”" in body
        assert "<cite>seeds/000_e382b17b02933558.txt:535</cite>" in body

    failed = found["MIS.UP.07"]
    assert len(re.findall(r'<g class="arrow tx( decided)?">', failed)) == 3
    assert len(re.findall(r'<g class="arrow rx( decided)?">', failed)) == 2
    assert failed.count('<g class="arrow') == FAILED_ARROWS
    assert len(re.findall(r'<g class="note( decided)?">', failed)) == 2
    assert failed.count(" decided\">") == 1
    assert '<text class="actor" x="' in failed and ">tester2</text>" in failed
    assert '<p class="detail">expected MISSION_REQUEST_INT seq=1 within 1.5 s; got nothing | ' \
           "&lt;script&gt;" in failed
    assert ">+0.000 s</text>" in failed and ">+1.500 s</text>" in failed
    assert "MUST, role vehicle, fails the run, took 0.310 s." in failed
    assert "no messages exchanged" in found["MIS.FENCE.01"]
    assert "Expected deviation: PX4 answers an empty download with an error &lt;ack&gt;" \
        in found["MIS.DL.02"]


def highlighted(body):
    """The indices (in exchange order) of the events drawn with the "decided" class."""
    drawn = re.findall(r'<g class="(?:arrow (?:tx|rx)|note)( decided)?">', body)
    return [index for index, decided in enumerate(drawn) if decided]


def test_the_event_the_check_recorded_is_the_one_highlighted(doc):
    clause = doc["clauses"][1]   # MIS.UP.07: 7 events, notes and both testers
    for index in (0, 4, 6):
        clause["decided_by"] = index
        body = sections(html_report(doc))["MIS.UP.07"]
        assert highlighted(body) == [index]
        assert body.count('class="decided-band"') == 1
        assert "the event that decided the verdict (as the check recorded it)." in body
    clause["decided_by"] = None   # none recorded: the guess from the verdict, said so
    body = sections(html_report(doc))["MIS.UP.07"]
    guess = deciding_event(clause, clause_events(doc, clause), clause_detail(doc, clause))
    assert highlighted(body) == [guess] and "(as read from the verdict)." in body


def test_passing_exchanges_are_folded(doc):
    text = html_report(doc)
    folded = re.findall(r'<details id="clause-([\w.]+)">(.*?)</details>', text, re.S)
    assert [clause_id for clause_id, _ in folded] == ["MIS.UP.01"]
    assert folded[0][1].count('<g class="arrow') == len(UPLOAD_OK)


def test_each_arrow_has_its_full_label_as_a_tooltip(doc):
    svg = sequence_diagram(UPLOAD_OK)
    labels = re.findall(r"<title>(.*?)</title>", svg)
    assert labels[0] == ("MISSION_COUNT count=1 mission_type=0 (MAV_MISSION_TYPE_MISSION) "
                         "target_system=1")
    assert labels[1] == "MISSION_REQUEST_INT seq=0 mission_type=0 (MAV_MISSION_TYPE_MISSION)"
    assert labels[2] == ("MISSION_ITEM_INT seq=0 param1=NaN param4=Infinity x=473977418 "
                         "y=85455939 z=10.0 mission_type=0 (MAV_MISSION_TYPE_MISSION)")
    assert labels[3] == ("MISSION_ACK type=0 (MAV_MISSION_ACCEPTED) mission_type=0 "
                         "(MAV_MISSION_TYPE_MISSION) opaque_id=1234")


def test_diagram_is_capped(doc):
    many = [event(i * 0.01, "tx" if i % 2 else "rx", "MISSION_ITEM_INT", seq=i)
            for i in range(MAX_EVENTS + 25)]
    svg = sequence_diagram(many)
    assert svg.count('<g class="arrow') == MAX_EVENTS
    assert "… 25 more events not drawn" in svg
    structure(svg)


def test_times_are_relative_to_the_first_event():
    svg = sequence_diagram([event(5.25, "tx", "MISSION_CLEAR_ALL"),
                            event(5.5, "note", "waited")])
    assert re.findall(r'<text class="time"[^>]*>([^<]*)</text>', svg) == ["+0.000 s", "+0.250 s"]


def test_a_passing_run_says_so(doc):
    for clause in doc["clauses"]:
        clause["outcome"], clause["gating"] = "pass", False
    doc["summary"]["verdict"] = "pass"
    doc["capture"] = None
    text = html_report(doc)
    structure(text)
    assert '<p class="verdict pass">✅ PASS' in text and "Every clause passed." in text
    assert sections(text) == {} and ".mcap" not in text
