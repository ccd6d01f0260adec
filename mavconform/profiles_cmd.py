"""`mavconform profiles`: the reference vehicle's profiles and what each changes.

Without options: one line per builtin profile. --show NAME|FILE: every knob the profile sets,
with the VARIANTS.md row it reproduces, its source and why (a `*` marks a knob whose sources
disagree; the alternative is printed under it), then the rows it covers without a knob.
--knobs: every knob a profile file may set. --json for machines. A profile file starts from
another (`base = "px4"`) and overrides knobs; use it with `mavconform vehicle --profile FILE`.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from mavconform.reference_impl.profiles import BUILTIN_PROFILES, KNOBS, Profile, load_profile


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("profiles", help="list the vehicle profiles and their knobs",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--show", metavar="NAME|FILE", help="every knob of one profile (builtin name or file)")
    p.add_argument("--knobs", action="store_true", help="every knob a profile file may set")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(run=run)


def _as_json(profile: Profile) -> dict[str, Any]:
    return {
        "name": profile.name, "description": profile.description,
        "knobs": [{"knob": s.knob, "value": s.value, "variant": s.variant, "source": s.source, "why": s.why,
                   "seen_on": s.seen_on, **({"alternative": vars(s.alternative)} if s.alternative else {})}
                  for s in profile.settings],
        "documented": [vars(d) for d in profile.documented],
    }


def run(args: argparse.Namespace) -> int:
    if args.knobs:
        if args.json:
            print(json.dumps([{"knob": k.name, "sets": f"{k.where}.{k.field}", "doc": k.doc}
                              for k in KNOBS.values()], indent=2))
        else:
            for k in KNOBS.values():
                print(f"{k.name:<26} {k.doc}")
        return 0
    if args.show:
        profile = load_profile(args.show)
        if args.json:
            print(json.dumps(_as_json(profile), indent=2))
            return 0
        print(f"{profile.name}: {profile.description}")
        if not profile.settings:
            print("  every knob at the spec default")
        for s in profile.settings:
            mark = "*" if s.alternative else " "
            seen = f" (seen on {s.seen_on})" if s.seen_on else ""
            print(f" {mark}{s.variant:<4} {s.knob} = {json.dumps(s.value)}\n        {s.why} [{s.source}]{seen}")
            if s.alternative:
                a = s.alternative
                print(f"        alternative {a.variant}: {s.knob} = {json.dumps(a.value)}: {a.why} [{a.source}]")
        for d in profile.documented:
            print(f"  {d.variant:<4} ({d.kind}) {d.why}" + (f" [{d.source}]" if d.source else ""))
        return 0
    profiles = [load_profile(name) for name in BUILTIN_PROFILES]
    if args.json:
        print(json.dumps([_as_json(p) for p in profiles], indent=2))
        return 0
    for p in profiles:
        print(f"{p.name:<15} {len(p.settings):>2} knobs  {p.description}")
    print("details: mavconform profiles --show NAME; targets: builtin:NAME; vehicle: "
          "mavconform vehicle --profile NAME|FILE")
    return 0
