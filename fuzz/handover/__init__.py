"""Safety of the handover under faults: whole delivery flights, random faults and GCS behaviours.

`world.py` builds and flies a `FlightCase` (a shipped scenario, a fault model per link
direction, a behaviour per GCS) in virtual time; `properties.py` states the five safety
properties precisely and judges them from probes on every node; `machine.py` draws cases with
Hypothesis and runs campaigns (`python -m mavconform.fuzz.handover --examples N --seed S`);
`variants.py` holds a broken vehicle per property and a flight that shows it failing.
"""

from .machine import CampaignResult, campaign, check, flight_cases, fly_and_judge
from .properties import PROPERTIES, Judge, Report, Violation
from .world import Behaviour, FlightCase, Link

__all__ = ["PROPERTIES", "Behaviour", "CampaignResult", "FlightCase", "Judge", "Link", "Report", "Violation",
           "campaign", "check", "flight_cases", "fly_and_judge"]
