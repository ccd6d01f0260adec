"""`python -m mavconform.fuzz.handover --examples N --seed S [--variant NAME]`: a longer campaign.

Flies N random delivery flights (machine.py) against the reference vehicle, or against one of
the broken variants (variants.py), and prints the figures: flights, handovers by outcome, the
longest handover against the bound, emergencies, the longest stale belief, and the first
violation, shrunk. Exit code 0 when every property held, 1 on a finding, 2 on a usage mistake.
"""

from __future__ import annotations

import argparse
import sys

from .machine import campaign
from .properties import PROPERTIES
from .variants import VARIANTS


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mavconform.fuzz.handover", description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=50, help="flights to fly (default 50)")
    parser.add_argument("--seed", type=int, default=0, help="the campaign's seed (default 0)")
    parser.add_argument("--variant", choices=sorted(VARIANTS), help="fly a deliberately broken vehicle")
    parser.add_argument("--no-shrink", action="store_true", help="report a finding as found")
    args = parser.parse_args(argv)
    if args.examples < 1:
        parser.error("--examples must be at least 1")
    factory = VARIANTS[args.variant][0] if args.variant else None
    print("properties:")
    for name, text in PROPERTIES.items():
        print(f"  {name} {text}")
    result = campaign(args.examples, args.seed, vehicle_factory=factory, shrink=not args.no_shrink)
    print(result.summary())
    return 1 if result.failure else 0


if __name__ == "__main__":
    sys.exit(main())
