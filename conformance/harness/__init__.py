"""The scripted peer: a GCS under the suite's exact control, and what it records."""
