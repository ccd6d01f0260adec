"""What the thesis's mission computer is loaded with (mission_computer.py is the machine):
`MissionComputerConfig`, checked when made, and `critical_path_budget`, the worst case its
default bound is meant to cover (docs/handover.md, "Bound")."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

from .emergency_procedure import EmergencyConfig
from .regions import Circle, Intersection, OwnedWaypoints, Polygon, RegionMethod, WaypointOwnership

THESIS_CHECK_PERIOD = 0.05   # s: "The third task runs each 50 milliseconds" (4.3.2)


@dataclass(frozen=True)
class MissionComputerConfig:
    """What the mission computer is loaded with (4.3.1: "GCS Parameters; GCS Geofences").

    `coverages` maps each GCS's system id to its coverage under one region method (a
    `Circle`, a `Polygon`, or the `OwnedWaypoints` it owns); a mapping is stored as sorted
    pairs so the config stays hashable. The default bound: see docs/handover.md, "Bound".
    """

    parent: int
    coverages: Any                        # Mapping[int, Coverage] in, tuple of pairs kept
    check_period: float = THESIS_CHECK_PERIOD
    dwell: float = 1.0                    # s inside (and outside) before an entry (exit) counts
    margin_m: float = 0.0                 # geographic methods: the Schmitt band around the edge
    acceptance_radius_m: float = 10.0     # waypoint method: "reached" within this distance
    bound: float = 40.0                   # s: every handover ends within this of its start
    closing_timeout: float | None = None  # s of the bound kept for steps 5-6 (None: bound / 4)
    resend_period: float = 1.0            # s between resends of the invitation / connect notice
    resends: int = 5                      # resends of each at most
    emergency: EmergencyConfig | None = None   # the emergency procedure (None: off, as before)

    def __post_init__(self) -> None:
        pairs = self.coverages.items() if isinstance(self.coverages, Mapping) else self.coverages
        pairs = tuple(sorted((int(k), v) for k, v in pairs))
        object.__setattr__(self, "coverages", pairs)
        ids = [k for k, _ in pairs]
        if len(ids) < 2:
            raise ValueError("a handover needs coverage for at least two GCSs")
        if len(set(ids)) != len(ids) or not all(1 <= k <= 255 for k in ids):
            raise ValueError(f"GCS system ids must be distinct, in 1..255: {ids}")
        if self.parent not in ids:
            raise ValueError(f"the parent GCS {self.parent} has no coverage")
        kinds = {type(v) for _, v in pairs}
        geographic = kinds <= {Circle, Polygon, Intersection}
        if not (geographic or kinds == {OwnedWaypoints}):
            raise ValueError("every GCS's coverage must be of one region method: circles/polygons, or waypoints, "
                             f"got {sorted(k.__name__ for k in kinds)}")
        if not geographic:
            WaypointOwnership.from_coverages({str(k): v for k, v in pairs})   # a waypoint owned twice
            if self.margin_m:
                raise ValueError("margin_m is for circles and polygons; the waypoint method has the "
                                 "acceptance radius")
        for name in ("check_period", "resend_period", "bound"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ValueError(f"{name} must be a positive number of seconds, got {getattr(self, name)!r}")
        for name in ("dwell", "margin_m", "acceptance_radius_m"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {getattr(self, name)!r}")
        closing = self.closing
        if not 0 < closing < self.bound:
            raise ValueError(f"closing_timeout {closing!r} must be more than 0 and less than the bound {self.bound!r}")
        if self.resends < 0:
            raise ValueError("resends must be >= 0")
        if self.emergency is not None and not isinstance(self.emergency, EmergencyConfig):
            raise TypeError(f"emergency must be an EmergencyConfig or None, got {self.emergency!r}")

    @property
    def closing(self) -> float:
        return self.bound / 4 if self.closing_timeout is None else self.closing_timeout

    @property
    def commit_timeout(self) -> float:
        """Seconds from a handover's start by which control must have moved, or it aborts."""
        return self.bound - self.closing

    @property
    def method(self) -> RegionMethod:
        kinds = {type(v) for _, v in self.coverages}
        if kinds == {OwnedWaypoints}:
            return RegionMethod.WAYPOINTS
        return RegionMethod.CIRCLE if kinds == {Circle} else RegionMethod.POLYGON

    @property
    def gcs_ids(self) -> tuple[int, ...]:
        return tuple(k for k, _ in self.coverages)

    def coverage(self, sysid: int) -> Any:
        return dict(self.coverages)[sysid]


def critical_path_budget(manager: Any, client: Any, *, resend_period: float = 1.0, resends: int = 5,
                         latency: float = 0.05) -> tuple[float, float]:
    """(commit, closing): how long steps 1-4 and 5-6 take when every message on the critical
    path gets through only on its last resend (each hop `latency` one way). `manager` is the
    vehicle's ManagerConfig, `client` the GCSs' ClientConfig. The default bound covers this
    with the engines' defaults (docs/handover.md, "Bound"; a test holds it to that)."""
    last = client.ack_timeout * client.max_retries            # a GCS command's last resend
    commit = (resend_period * resends                         # 1: invitation
              + last                                          # 2: the partner's request
              + manager.notify_timeout * manager.notify_retries   # 2: the forward to the commander
              + last                                          # 3: the commander's allow
              + manager.status_period + last                  # 4: CONTROL_STATUS, then the request again
              + 6 * latency)
    closing = max(resend_period * resends + latency,          # 5: connect notice and its ACK
                  manager.status_period + last + latency)     # 6: CONTROL_STATUS, then the release
    return commit, closing
