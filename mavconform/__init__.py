"""The `mavconform` command line: one front door to the vehicle, the GCS and the suites."""

__version__ = "0.1.0"
