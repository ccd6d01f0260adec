"""Mutant reference GCSs that break the set-current clauses (MIS.G.SC.*); see mutants.py."""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.mission.actions import Finished
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.constants import Cmd

from .mutants import _SkipsResend, client_mutant, gcs_mutant


class _SetCurrentPlusOne(MissionClient):
    def set_current(self, seq, now, *, via_command=False):
        return super().set_current(seq + 1, now, via_command=via_command)   # "seq 0 is home"


class _SetCurrentLingers(MissionClient):
    """Its resend timer outlives the confirmation: one more set-current goes out after it."""

    _linger: tuple[float, Any] | None = None

    def _on_set_current_reply(self, op, msg, name, now):
        out = super()._on_set_current_reply(op, msg, name, now)
        if op is not None and any(isinstance(a, Finished) for a in out):
            self._linger = (now + self.timings.default_timeout, op.last_sent)
        return out

    def poll(self, now):
        out = super().poll(now)
        if self._linger is not None and now >= self._linger[0]:
            out.append(self._to_target(self._linger[1]))
            self._linger = None
        return out

    def next_deadline(self):
        times = [t for t in (super().next_deadline(), self._linger and self._linger[0]) if t is not None]
        return min(times) if times else None


class _IgnoresMissionCurrent(MissionClient):
    def _on_set_current_reply(self, op, msg, name, now):
        if name == "MISSION_CURRENT":
            return []   # waits for an answer of its own to the set-current
        return super()._on_set_current_reply(op, msg, name, now)


class _NoSetCurrentResend(_SkipsResend):
    """Sends the set-current once; its timer still runs, and the operation times out after it."""

    def skipped(self, msg):
        return msg._type == "MISSION_SET_CURRENT" or (msg._type == "COMMAND_LONG"
                                                       and msg.command == Cmd.DO_SET_MISSION_CURRENT)


gcs_mutant("set-current-plus-one", "sends set-current for seq+1, taking seq 0 for the home position",
           {"MIS.G.SC.01"}, client_mutant(_SetCurrentPlusOne))
gcs_mutant("ignores-mission-current", "ignores MISSION_CURRENT: resends set-current until it gives up",
           {"MIS.G.SC.01", "MIS.G.SC.02", "MIS.G.SC.03"}, client_mutant(_IgnoresMissionCurrent))
gcs_mutant("set-current-lingers", "resends set-current once more after MISSION_CURRENT confirmed it",
           {"MIS.G.SC.02"}, client_mutant(_SetCurrentLingers))
gcs_mutant("no-set-current-resend", "sends set-current once and never again when no MISSION_CURRENT "
           "confirms it (it still waits out its timeout)", {"MIS.G.SC.03"}, client_mutant(_NoSetCurrentResend))
