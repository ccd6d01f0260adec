"""Fault schedules (the JSON a step carries) -> `FaultModel`s on GCS A's link.

A schedule is drawn by `fuzz.strategies.fault_schedules`; it is data so a saved case can
replay it. Times in it are relative (a burst starts `start` seconds after the schedule is
set), so the same case means the same thing whenever its step runs. The one fault the
reference `FaultModel` cannot express on its own, a partition that begins at a chosen
message rather than at a chosen time, is the `CutAfter` rule here.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from mavconform.reference_impl.net import DropMessage, FaultModel, MessageRule

_DIRECT = ("loss", "duplicate", "reorder", "reorder_delay", "delay", "jitter", "corrupt")


@dataclass(eq=False)
class CutAfter(MessageRule):
    """From the `nth` message called `name` on, drop it and the next `span - 1` messages of
    any kind: a partition triggered by the protocol's own progress. Counted in messages,
    not seconds, so it always ends (every retry it swallows counts towards `span`)."""

    name: str
    nth: int
    span: int
    seen: int = field(default=0, init=False)
    left: int = field(default=0, init=False)

    def observe(self, msg: Any) -> bool:
        if self.left:
            self.left -= 1
            return True
        if self.seen < self.nth and msg.get_type() == self.name:
            self.seen += 1
            if self.seen == self.nth:
                self.left = self.span - 1
                return True
        return False

    def fresh(self) -> "CutAfter":
        return CutAfter(self.name, self.nth, self.span)


def build_fault_model(spec: dict[str, Any] | None, now: float) -> FaultModel:
    """The `FaultModel` a schedule describes, its bursts placed after `now`; None: clean."""
    if not spec:
        return FaultModel()
    rules: list[MessageRule] = [DropMessage(d["name"], int(d["nth"]), bool(d.get("onwards")))
                                for d in spec.get("drops", ())]
    cut = spec.get("cut")
    if cut:
        rules.append(CutAfter(cut["name"], int(cut["nth"]), max(1, int(cut["span"]))))
    bursts = tuple(sorted((now + float(s), now + float(s) + float(n)) for s, n in spec.get("bursts", ())))
    return FaultModel(**{k: float(spec[k]) for k in _DIRECT if k in spec},
                      partitions=bursts, rules=tuple(rules))


def install(held: FaultModel, new: FaultModel) -> None:
    """Make the model a driver already holds behave like `new`, in place.

    Drivers take a link's FaultModel once (SimNetwork.connect, UdpDriver.add_node); setting
    the fields of that same object changes the faults without reconnecting, which would
    also re-seed the link's random generator."""
    for f in dataclasses.fields(FaultModel):
        if f.init and f.name != "dialect":
            setattr(held, f.name, getattr(new, f.name))
