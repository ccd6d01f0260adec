#!/usr/bin/env python3
"""The reference GCS as a GCS command: what `mavconform run --role gcs --gcs-cmd` runs.

    python tools/gcs_adapters/reference_gcs.py PORT OP JOBFILE

The same GCS `--target builtin:gcs` runs in-process, here behind the command contract
(docs/gcs-conformance.md), so the command path itself (a process per operation, the job
file, the result file, the bound) is exercised by a GCS known to pass every clause. It
sends to 127.0.0.1:PORT first, finds the vehicle by its HEARTBEAT, runs the one operation
with its own timeouts and retries, writes the result file and exits 0 on success, 1 on
failure, 2 on a bad job. A vehicle that never sends a HEARTBEAT is a failure after 5 s.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mavconform.conformance.gcs.job import JobResult, read_job, write_result
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.mission.adaptations import NONE
from mavconform.reference_impl.net import UdpDriver
from mavconform.reference_impl.session import GcsSession, TargetUnresponsive

HOST = "127.0.0.1"
DISCOVERY_S = 5.0


def main(argv: list[str]) -> int:
    if len(argv) != 3 or argv[1] not in ("upload", "download", "clear", "set-current"):
        print("usage: reference_gcs.py PORT upload|download|clear|set-current JOBFILE", file=sys.stderr)
        return 2
    try:
        port = int(argv[0])
        job, result_file = read_job(Path(argv[2]))
    except ValueError as exc:
        print(f"reference_gcs: {exc}", file=sys.stderr)
        return 2
    gcs = GcsNode(GcsConfig(adaptations=NONE), remote=(HOST, port))
    with UdpDriver() as driver:
        driver.add_node(gcs, bind=(HOST, 0))
        session = GcsSession(driver, gcs)
        try:
            session.wait_for_target(DISCOVERY_S)
        except TargetUnresponsive as exc:
            result = JobResult(False, str(exc))
        else:
            if job.op == "upload":
                done = session.upload(job.mission_type, job.items)
            elif job.op == "download":
                done = session.download(job.mission_type)
            elif job.op == "clear":
                done = session.clear(job.mission_type)
            else:
                done = session.set_current(job.seq)
            result = JobResult(done.ok, done.summary(), items=done.items)
        driver.run_for(0.05)   # what went out with the result (a download's final ACK) leaves the socket
    write_result(result_file, result)
    print(result.said)
    return 0 if result.ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
