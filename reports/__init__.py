"""Reports of a conformance run: pure functions from the run document to files.

`run_document` defines and checks the document (format "mavconform-run/2"); `junit`,
`markdown` and `html` render it; `write` puts all of them in a folder. The MCAP capture is
recorded by the runner during the run and only linked from here.
"""

from mavconform.reports.html import html_report
from mavconform.reports.junit import junit_xml
from mavconform.reports.markdown import markdown_summary
from mavconform.reports.run_document import FORMAT, OUTCOMES, check_run, dump_run, load_run
from mavconform.reports.write import write_reports

__all__ = ["FORMAT", "OUTCOMES", "check_run", "dump_run", "html_report", "junit_xml", "load_run",
           "markdown_summary", "write_reports"]
