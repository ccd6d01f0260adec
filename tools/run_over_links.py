"""`make run-links`: the whole suite against the reference vehicle served over each link.

Starts `mavconform vehicle` on UDP, on TCP (tcpin), and behind pseudo-terminals paced at
57600 and 921600 baud, runs `mavconform run` against each (side by side: the runs wait
far more than they compute), writes reports under reports/links/<link>/, and prints the
outcome counts per link. Exit 0 only if every run exits 0 and every link gives every
clause the same outcome as UDP: the link may change how long things take, never a verdict.

    python tools/run_over_links.py [--out reports/links] [LINK ...]   (LINK: udp tcp pty57600 pty921600)
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

LINKS = {"udp": "udp:127.0.0.1:0", "tcp": "tcpin:0", "pty57600": "pty:57600", "pty921600": "pty:921600"}
RUN_TIMEOUT = 600   # s: a whole run at 57600 baud takes well under a minute


def _target(link: str, printed: str) -> str:
    """What the suite connects to, from the address the vehicle printed."""
    return printed.replace("tcpin:", "tcp:", 1) if link == "tcp" else printed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="reports/links", help="report folders go here (default %(default)s)")
    parser.add_argument("links", nargs="*", metavar="LINK", help=f"of {', '.join(LINKS)} (default: all)")
    args = parser.parse_args(argv)
    unknown = [link for link in args.links if link not in LINKS]
    if unknown:
        parser.error(f"unknown link {unknown[0]!r} (known: {', '.join(LINKS)})")
    links = ["udp"] + [link for link in args.links or LINKS if link != "udp"]
    vehicles, runs = {}, {}
    try:
        for link in links:
            vehicles[link] = subprocess.Popen(
                [sys.executable, "-m", "mavconform", "vehicle", "--listen", LINKS[link], "--quiet",
                 "--duration", str(RUN_TIMEOUT + 60)], stdout=subprocess.PIPE, text=True)
        for link in links:
            line = vehicles[link].stdout.readline()   # the vehicle exits after --duration at the latest
            if "listening on " not in line:
                print(f"run-links: the vehicle on {link} did not start: {line.strip()!r}", file=sys.stderr)
                return 1
            target = _target(link, line.split("listening on ")[1].split()[0])
            out = Path(args.out) / link
            runs[link] = subprocess.Popen(
                [sys.executable, "-m", "mavconform", "run", "--target", target, "--report-dir", str(out), "-q"],
                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        codes = {link: run.wait(timeout=RUN_TIMEOUT) for link, run in runs.items()}
        for link, run in runs.items():
            print(f"--- {link}:\n{run.stdout.read().rstrip()}")
    finally:
        for proc in [*vehicles.values(), *runs.values()]:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)
    return _compare(links, codes, Path(args.out))


def _compare(links: list[str], codes: dict[str, int], out: Path) -> int:
    docs = {link: json.loads((out / link / "run.json").read_text()) for link in links}
    outcomes = {link: {c["id"]: c["outcome"] for c in doc["clauses"]} for link, doc in docs.items()}
    print(f"\n{'link':<10} {'exit':>4} {'pass':>5} {'fail':>5} {'n/a':>5} {'error':>5}  bytes/s  reply +s  differs from udp")
    bad = False
    for link in links:
        s, run_link = docs[link]["summary"], docs[link]["run"]["link"]
        differ = sorted(cid for cid, o in outcomes[link].items() if outcomes["udp"].get(cid) != o)
        bad |= codes[link] != 0 or bool(differ)
        rate = run_link["bytes_per_second"]
        udp = outcomes["udp"]
        said = ", ".join(f"{c} ({outcomes[link][c]}, udp {udp.get(c)})" for c in differ) or "none"
        print(f"{link:<10} {codes[link]:>4} {s['pass']:>5} {s['fail']:>5} {s['not-applicable']:>5} {s['error']:>5}"
              f"  {'-' if rate is None else f'{rate:g}':>7}  {run_link['reply_allowance_s']:>8g}  "
              f"{said}")
    print("run-links: " + ("FAIL" if bad else "every link: exit 0, the same outcome for every clause as over UDP"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
