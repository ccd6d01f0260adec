"""Every report reads in one order (issue 29): what fails the run, the known deviations with
what excuses each, what else did not pass, then the clauses that do not apply or were
skipped, one group per reason. The terminal summary says it the same way."""

from mavconform.reports.reading_order import group_title, reading_order
from mavconform.run_cmd import reading_lines

from .sample import clause


def test_the_parts_and_their_order(doc):
    doc["clauses"].append(clause("MIS.UP.09", "fail", [], level="SHOULD", detail="8 resends"))
    order = reading_order(doc)
    assert [c["id"] for c in order.failing] == ["MIS.UP.07", "MIS.CUR.04"]
    assert [c["id"] for c in order.deviations] == ["MIS.DL.02"]
    assert [c["id"] for c in order.other] == ["MIS.UP.09"]
    assert [(g.outcome, [c["id"] for c in g.clauses]) for g in order.groups] == [
        ("not-applicable", ["MIS.FENCE.01"]), ("skipped", ["MIS.CLR.03"])]
    assert [c["id"] for c in order.listed] == ["MIS.UP.07", "MIS.CUR.04", "MIS.DL.02", "MIS.UP.09",
                                               "MIS.FENCE.01", "MIS.CLR.03"]


def test_clauses_that_do_not_apply_for_one_reason_are_one_group_in_the_order_first_met(doc):
    reason = "the target sent no CONTROL_STATUS: no system manager"
    for n in range(1, 22):
        doc["clauses"].append(clause(f"HO.CTL.{n:02d}", "not-applicable", [], detail=reason))
    groups = reading_order(doc).groups
    assert [len(g.clauses) for g in groups] == [1, 21, 1]
    assert group_title(groups[1]) == f"21 clauses not applicable: {reason}"
    lines = reading_lines(doc)
    at = lines.index(f"21 clauses not applicable: {reason}")
    assert lines[at + 1].startswith("  HO.CTL.01, HO.CTL.02,") and all(len(line) <= 100 for line in lines)


def test_the_terminal_lists_the_same_order_with_what_excuses_each_deviation(doc):
    lines = reading_lines(doc)
    heads = [line for line in lines if not line.startswith(" ")]
    assert heads[:2] == ["fails the run (2):", "known deviations (1):"]
    deviation = lines.index("known deviations (1):")
    assert lines[deviation + 1].split()[:2] == ["KNOWN", "MIS.DL.02"]
    assert lines[deviation + 2].startswith("        excused: ")
    for item in doc["clauses"]:      # nothing fails: no "fails the run" line at all
        item["gating"] = False
    assert not any(line.startswith("fails the run") for line in reading_lines(doc))
