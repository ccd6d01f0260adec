"""Report writers: JSON, JUnit, Markdown, HTML, MCAP."""
