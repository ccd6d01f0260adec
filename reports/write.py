"""Write every report of a run into one folder: run.json, run.junit.xml, run.md, run.html.

All four are rendered before the first is written, so a run never leaves a half-written
set behind a rendering bug. The MCAP capture is not written here: the runner records it
while the run happens, and the document names it (`capture`) so the reports can link it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, NoReturn

from mavconform.reference_impl.errors import UsageError
from mavconform.reports.html import html_report
from mavconform.reports.junit import junit_xml
from mavconform.reports.markdown import markdown_summary
from mavconform.reports.run_document import check_run, dump_run

SUFFIXES = {"json": ".json", "junit": ".junit.xml", "markdown": ".md", "html": ".html"}


def write_reports(doc: dict[str, Any], directory: str | Path, *,
                  basename: str = "run") -> dict[str, Path]:
    """Write the reports of `doc` into `directory` (created if missing).

    Returns the paths by kind: "json", "junit", "markdown", "html". A document of the wrong
    shape, or a folder or file that cannot be written, is a one-line `UsageError`.
    """
    check_run(doc)
    texts = {"json": dump_run(doc), "junit": junit_xml(doc), "markdown": markdown_summary(doc),
             "html": html_report(doc, folder=directory)}
    return write_texts(directory, {kind: (f"{basename}{suffix}", texts[kind]) for kind, suffix in SUFFIXES.items()})


def write_texts(directory: str | Path, texts: dict[str, tuple[str, str]]) -> dict[str, Path]:
    """Write each (file name, text) of `texts` into `directory` (created if missing), all
    rendered before any is written; the paths by the same keys. A folder or file that cannot
    be written is a one-line `UsageError`."""
    folder = Path(directory)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        _fail(f"{directory}: cannot create folder: {error.strerror or error}")
    paths = {kind: folder / name for kind, (name, _) in texts.items()}
    for kind, path in paths.items():
        try:
            path.write_text(texts[kind][1], encoding="utf-8", newline="\n")
        except OSError as error:
            _fail(f"{path}: cannot write: {error.strerror or error}")
    return paths


def _fail(message: str) -> NoReturn:
    raise UsageError(" ".join(message.split())) from None  # one line, even for odd paths
