"""What several commands share: checked numeric arguments, link faults, MCAP capture.

A bad value raises argparse's ArgumentTypeError, which the parser turns into one line
naming the option, and exit code 2.
"""

from __future__ import annotations

import argparse
import contextlib
from typing import Any, Callable, Iterator

from mavconform.reference_impl.net import FaultModel, McapCapture, parse_drop_rule


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def probability(text: str) -> float:
    value = _number(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a probability in [0, 1]")
    return value


def non_negative(text: str) -> float:
    value = _number(text)
    if not value >= 0.0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} must be a finite number >= 0")
    return value


def positive(text: str) -> float:
    value = _number(text)
    if not value > 0.0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} must be a finite number > 0")
    return value


MAX_TIME_SCALE = 100.0   # a stretch past this is a typo: every wait of a run times it


def time_scale(text: str) -> float:
    """--time-scale: more than 0, at most MAX_TIME_SCALE (1e308 would make every wait endless)."""
    value = positive(text)
    if value > MAX_TIME_SCALE:
        raise argparse.ArgumentTypeError(f"{text!r} must be at most {MAX_TIME_SCALE:g}")
    return value


MAX_CLOCK_SPEED = 16.0   # past this, scheduling jitter (x speed) eats the protocol's bounds


def clock_speed(text: str) -> float:
    """--clock-speed: more than 0, at most MAX_CLOCK_SPEED."""
    value = positive(text)
    if value > MAX_CLOCK_SPEED:
        raise argparse.ArgumentTypeError(f"{text!r} must be at most {MAX_CLOCK_SPEED:g}")
    return value


def seconds_up_to(high: float) -> Callable[[str], float]:
    """An argparse type: a number of seconds, more than 0 and at most `high`."""
    def parse(text: str) -> float:
        value = positive(text)
        if value > high:
            raise argparse.ArgumentTypeError(f"{text!r} must be at most {high:g} seconds")
        return value
    return parse


def _whole(text: str, low: int, high: int, what: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(f"{text!r} is not {what} in {low}..{high}")
    return value


def mavlink_id(text: str) -> int:
    return _whole(text, 1, 255, "a MAVLink id")


def seq_number(text: str) -> int:
    return _whole(text, 0, 0xFFFF, "a mission item number")


def add_fault_options(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group(
        "link faults", "applied to every datagram in both directions, decided by --seed")
    g.add_argument("--loss", type=probability, default=0.0, metavar="P", help="drop probability (0..1)")
    g.add_argument("--dup", type=probability, default=0.0, metavar="P", help="duplication probability")
    g.add_argument("--reorder", type=probability, default=0.0, metavar="P",
                   help="probability a datagram is held back so later ones overtake it")
    g.add_argument("--delay-ms", "--delay", type=non_negative, default=0.0, metavar="MS", help="one-way latency")
    g.add_argument("--jitter-ms", "--jitter", type=non_negative, default=0.0, metavar="MS", help="extra random latency 0..MS")
    g.add_argument("--corrupt", type=probability, default=0.0, metavar="P", help="probability of flipped bytes")
    g.add_argument("--drop", action="append", default=[], metavar="RULE",
                   help="drop by message: NAME (every one), NAME#N (the Nth), NAME#N+ (Nth onwards); "
                        "repeatable, e.g. --drop MISSION_ACK#1")
    g.add_argument("--seed", type=int, default=0, help="seed of the fault decisions (default 0)")


def fault_model(args: argparse.Namespace) -> FaultModel | None:
    """The FaultModel the options describe, or None when no fault was asked for."""
    rules = tuple(parse_drop_rule(text) for text in args.drop)
    model = FaultModel(loss=args.loss, duplicate=args.dup, reorder=args.reorder,
                       delay=args.delay_ms / 1000, jitter=args.jitter_ms / 1000,
                       corrupt=args.corrupt, rules=rules)
    return None if model.is_clean else model


def describe_faults(args: argparse.Namespace) -> str:
    parts = [f"{name} {getattr(args, attr):g}" for name, attr in (
        ("loss", "loss"), ("dup", "dup"), ("reorder", "reorder"), ("corrupt", "corrupt"))
        if getattr(args, attr)]
    if args.delay_ms or args.jitter_ms:
        parts.append(f"delay {args.delay_ms:g}+{args.jitter_ms:g} ms")
    parts += [f"drop {rule}" for rule in args.drop]
    return ", ".join(parts) if parts else "none"



@contextlib.contextmanager
def capture_to(driver: Any, path: str | None) -> Iterator[None]:
    """Record every datagram the driver moves into an MCAP file at `path` (if given), and
    close the file however the block ends, so a capture is never left unreadable."""
    if path is None:
        yield
        return
    capture = McapCapture(path)
    driver.add_capture(capture)
    try:
        yield
    finally:
        capture.close()
