import re

from mavconform.reports.markdown import markdown_summary


def table_rows(text, first_header):
    """Rows (lists of cells) of the table whose header starts with `first_header`."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(f"| {first_header} |"))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        # a cell ends at a pipe that is not escaped
        rows.append([cell.strip() for cell in re.split(r"(?<!\\)\|", line)[1:-1]])
    return rows


def test_header_names_verdict_target_identity_and_tool(doc):
    header = markdown_summary(doc).splitlines()[0]
    assert header.startswith("## ❌ FAIL: udp:127.0.0.1:14550 \\<b\\>\\|")
    assert "system 1 component 1, type 2, autopilot 4, MAVLink 2, at 127.0.0.1:40001" in header
    assert header.endswith("mavconform 0.1.0")

    doc["summary"]["verdict"] = "pass"
    doc["identity"] = None
    header = markdown_summary(doc).splitlines()[0]
    assert header.startswith("## ✅ PASS") and "no answer from the target" in header


def test_counts_table(doc):
    rows = table_rows(markdown_summary(doc), "Outcome")
    assert rows == [["✅ pass", "1"], ["❌ fail", "1"], ["⚠️ known-deviation", "1"],
                    ["➖ not-applicable", "1"], ["⏭️ skipped", "1"], ["💥 error", "1"],
                    ["**total**", "**6**"]]


def test_every_clause_not_passing_is_a_row_with_escaped_cells(doc):
    """Issue 29: what fails the run, then the known deviations with what excuses each, then
    the clauses that do not apply or were skipped, one folded line per reason."""
    text = markdown_summary(doc)
    assert text.index("### Fails the run (2)") < text.index("### Known deviations (1)")
    rows = table_rows(text, "Clause | Level | Outcome | Title | Detail")
    assert [row[0] for row in rows] == ["MIS.UP.07", "MIS.CUR.04"]
    deviations = table_rows(text, "Clause | Level | Title | Excused by | Detail")
    assert [row[0] for row in deviations] == ["MIS.DL.02"] and deviations[0][3]
    folded = re.findall(r"<details><summary>(\S+) (\d+) clauses? ([\w ]+?):", text)
    assert folded == [("➖", "1", "not applicable"), ("⏭️", "1", "skipped")]
    assert text.index("### Known deviations") < text.index("<details><summary>➖ 1 clause not applicable")
    assert all(len(row) == 5 for row in rows)  # no pipe from the data split a cell
    failing = rows[0]
    assert failing[1:3] == ["MUST", "❌ fail (gating)"]
    detail = failing[4]
    assert detail.startswith("expected MISSION\\_REQUEST\\_INT seq=1 within 1.5 s; got nothing \\|")
    assert "\\<script\\>" in detail and "<script>" not in text
    assert len(re.sub(r"\\(.)", r"\1", detail)) <= 200  # unescaped length
    assert "\x00" not in text and "\x1b" not in text and "\u202e" not in text


def test_regressions_and_capture(doc):
    text = markdown_summary(doc)
    assert "### Regressions against the baseline (1)\n\n- MIS.UP.07: MIS.UP.07 in our words" in text
    assert "### Fixed since the baseline (1)\n\n- MIS.GONE.01\n" in text
    assert "[run 1.mcap](run%201.mcap)" in text
    doc["gating"]["regressions"] = []
    doc["capture"] = None
    text = markdown_summary(doc)
    assert "Regressions" not in text and ".mcap" not in text


def test_full_matrix_is_folded(doc):
    text = markdown_summary(doc)
    folded = text[text.index("<details><summary>All 6 clauses</summary>\n\n"):]
    assert folded.rstrip().endswith("</details>")
    rows = table_rows(folded, "Clause | Level | Outcome | Title")
    assert [row[0] for row in rows] == [c["id"] for c in doc["clauses"]]
