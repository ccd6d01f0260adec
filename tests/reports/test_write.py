import json
import xml.etree.ElementTree as ET

import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reports.run_document import dump_run, load_run
from mavconform.reports.write import write_reports


def test_writes_every_report(doc, tmp_path):
    folder = tmp_path / "out" / "deeper"
    paths = write_reports(doc, folder)
    assert paths == {"json": folder / "run.json", "junit": folder / "run.junit.xml",
                     "markdown": folder / "run.md", "html": folder / "run.html"}
    assert load_run(paths["json"]) == doc
    assert paths["json"].read_bytes() == dump_run(doc).encode("utf-8")
    ET.parse(paths["junit"])
    assert paths["markdown"].read_text(encoding="utf-8").startswith("## ❌ FAIL")
    assert "<svg" in paths["html"].read_text(encoding="utf-8")
    assert sorted(p.name for p in folder.iterdir()) == [
        "run.html", "run.json", "run.junit.xml", "run.md"]


def test_basename(doc, tmp_path):
    paths = write_reports(doc, tmp_path, basename="px4")
    assert sorted(p.name for p in paths.values()) == [
        "px4.html", "px4.json", "px4.junit.xml", "px4.md"]
    assert json.loads(paths["json"].read_text(encoding="utf-8"))["format"] == "mavconform-run/2"


def test_a_folder_that_cannot_be_made_is_one_line(doc, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(UsageError) as caught:
        write_reports(doc, blocker / "reports")
    assert str(caught.value).startswith(f"{blocker / 'reports'}: cannot create folder: ")
    assert "\n" not in str(caught.value)


def test_a_file_that_cannot_be_written_is_one_line(doc, tmp_path):
    (tmp_path / "run.md").mkdir()
    with pytest.raises(UsageError, match=r"run\.md: cannot write: Is a directory$"):
        write_reports(doc, tmp_path)


def test_a_bad_document_is_refused_before_anything_is_written(doc, tmp_path):
    del doc["clauses"][2]["outcome"]
    with pytest.raises(UsageError, match=r"^run document: clauses\[2\]: missing 'outcome'$"):
        write_reports(doc, tmp_path / "out")
    assert not (tmp_path / "out").exists()
