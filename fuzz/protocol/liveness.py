"""The protocol fuzzer's liveness oracle (target-hang, target-crash): after every step a third
GCS asks for the mission list over a clean link, retried as a GCS would, and the answer's
count is judged against the plans the vehicle may hold. A mixin of `steps.Runner`, whose
world, plan versions and violations it uses."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionType

from ..case import Violation

if TYPE_CHECKING:
    from .versions import Versions
    from .world import World

HEARTBEAT_SILENCE = 3.0   # s without a HEARTBEAT (a 1 Hz stream) that make a silent target a crashed one


class Liveness:
    """The probe; `steps.Runner` supplies `world`, `versions`, `_violation`, `_wire_status`
    and `_raise_tool_crash`."""

    world: "World"
    versions: "Versions"

    def _probe(self) -> Violation | None:
        """MISSION_REQUEST_LIST from a third GCS over a clean link, retried like a GCS would;
        a MISSION_COUNT (or any MISSION_ACK, e.g. DENIED) to it is an answer. A download it
        opens is closed at once, so the probe leaves the vehicle as it found it."""
        w = self.world
        t = w.profile.timings
        with w.faults_lifted():
            for _ in range(t.max_retries + 1):
                if self._ask_list(MissionType.MISSION):
                    return self._counted(MissionType.MISSION) or (
                        None if w.virtual else self._other_counts()) or (
                        None if w.wire is None else self._wire_status())
                age = w.heartbeat_age()
                if age is not None and age > HEARTBEAT_SILENCE:
                    break          # silent altogether: no use asking again
        self._raise_tool_crash()
        asked = f"MISSION_REQUEST_LIST (asked every {t.default_timeout:g} s)"
        crashed = w.crashes()
        if crashed:
            return self._violation("target-crash", f"the vehicle raised and fell silent: {crashed[0]}")
        age = w.heartbeat_age()
        if age is not None and age > HEARTBEAT_SILENCE:
            return self._violation("target-crash", (
                f"the target fell silent: no HEARTBEAT for {_seconds(age)} and no answer to {asked}"))
        beating = "" if age is None else " although its HEARTBEAT still comes"
        return self._violation("target-hang", f"the vehicle did not answer {asked}{beating}")

    def _ask_list(self, t: MissionType) -> bool:
        """The probe asks for `t`'s list once: a MISSION_COUNT (or any MISSION_ACK, e.g.
        DENIED) to it within the profile's timeout is an answer."""
        w, probe = self.world, self.world.probe
        me = probe.system
        probe.listen()
        probe.send_raw(m.request_list_message(t, w.target))
        return w.run_until(lambda: any(msg._type in ("MISSION_COUNT", "MISSION_ACK") and msg.target_system == me
                                       for msg in probe.heard), w.profile.timings.default_timeout)

    def _counted(self, t: MissionType) -> Violation | None:
        """Judge the MISSION_COUNT the probe heard for `t` (if any) against the lengths of
        the plans the vehicle may hold, and close the download it opened."""
        w, probe = self.world, self.world.probe
        count = probe.counts.get(int(t))
        if count is not None and not self.versions.allows_count(t, count):
            return self._violation("download-matches-upload", (
                f"the vehicle reports {count} {t.label} items (MISSION_COUNT to a MISSION_REQUEST_LIST), "
                f"but every version it may hold has another length ({self.versions.describe(t)})"))
        if count:
            probe.send_raw(m.ack_message(MissionResult.OPERATION_CANCELLED, t, w.target))
            w.run_until(_always, 0.0)
        return None

    def _other_counts(self) -> Violation | None:
        """Over the wire the store cannot be read: the fence and rally counts are asked
        too (one try each, a few milliseconds), so a plan of the wrong length is seen after
        the step that made it, not only when a download happens to follow."""
        for t in (MissionType.FENCE, MissionType.RALLY):
            if self._ask_list(t):
                v = self._counted(t)
                if v is not None:
                    return v
        return None

    def _raise_tool_crash(self) -> None:
        """One of our own GCS nodes raised: that is our bug, never the target's."""
        exc = self.world.tool_crash()
        if exc is not None:
            raise exc


def _always() -> bool:
    return True


def _seconds(value: float) -> str:
    return "the whole example" if value == float("inf") else f"{value:.1f} s"
