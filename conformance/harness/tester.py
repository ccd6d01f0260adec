"""`Tester`: what a check holds. Send exactly what the script says; expect, with a bound.

Every wait is bounded and ends on the event it waits for: `expect` returns the moment a
matching frame arrives; only `expect_silence` and `collect` must sit out their whole
window, and those windows are what the suite's forced-wait figure counts. All times a
check passes are the protocol's own (spec defaults) and are stretched by `--time-scale`; a
slow link (a serial line) adds its `link_allowance` to each reply wait.

Frames are matched from a floor (`mark()` moves it to "now") and a matched frame is
consumed, so two `expect`s of the same request see the first copy and then the retry.
While a wait runs, each wake-up looks only at the frames that came since the last one
(`_arrival`): a busy target's stream (hundreds of frames/s over a flight) scanned again
from the floor at every datagram would cost the loop more than it has, and a loop that
falls behind lets the kernel drop what the target sends.

Each waiting helper also records which exchange event decided the clause, so the report
marks the message the check judged: `expect`, `poll_for` and `collect` the last frame they
consume; an `expect` that times out, the note it writes; a `poll_for` or `collect` that
gets nothing, the last message this tester sent (it went unanswered); a failing
`expect_silence`, the frame that broke the silence. The last one recorded before the
verdict is the clause's `decided_by`. A check whose verdict is about an earlier frame says
so (`decided_by_frame`). The record lives in the clause's `Exchange` (the runner starts a
new one per clause; both GCSs share it), not at the floor: checks `mark()` mid-clause.
"""

from __future__ import annotations

import contextlib
from typing import Any, Callable, Iterator, Protocol

from mavconform.reference_impl.mission.timing import Timings
from mavconform.reference_impl.wire.frame import Frame

from ..outcome import ClauseFailed, TargetUnresponsive
from .exchange import Exchange, message_fields, relevant, used
from .float_forms import INT_TO_FLOAT, to_float, widen
from .match import Match
from .measured import Measured
from .stored_form import SPEC_FORM, StoredForm
from .tester_node import TesterNode

SPEC = Timings()
LIVENESS = 3.0   # s without any frame from the target, beyond which it is unresponsive
KEEP_FRAMES = 100_000   # frames kept before the floor (checks may look back, e.g. for HEARTBEATs)
KEEP_DRAWN = 50_000     # received frames remembered with their exchange event (for `decided_by`)


class Driver(Protocol):
    def run_until(self, condition: Callable[[], bool], *, timeout: float) -> bool: ...


class Tester:
    def __init__(self, node: TesterNode, driver: Any, *, scale: float = 1.0,
                 timings: Timings = SPEC) -> None:
        self.node = node
        self.driver = driver
        self.scale = scale
        # s a slow link adds to a reply (a request and its answer, behind what is queued):
        # added to every reply wait (`expect`, `poll_for`), set by the session from the link
        # (harness/link_timing.py); 0 on a network link
        self.link_allowance = 0.0
        # False for a target that answers only MISSION_ITEM / MISSION_REQUEST (float_forms.py,
        # found before the first clause); `translate`: the clause lets the tester use them
        self.int_forms = True
        self.translate = True
        self._told: Exchange | None = None   # the exchange already told of the translation
        self.timings = timings
        self.target: tuple[int, int] = node.target or (0, 0)
        self.form: StoredForm = SPEC_FORM    # how the target keeps plans (set on discovery)
        self.exchange: Exchange | None = None
        self.forced_wait = 0.0
        self._floor = 0
        self._consumed: set[int] = set()   # ids of matched frames past the floor
        self.touched_types: set[int] = set()   # every mission_type sent, invalid ones too (cleanup)
        # mission_type -> opaque_id the vehicle's last MISSION_ACK ACCEPTED gave it, to any of
        # the session's GCSs (shared between them; kept by `record_traffic`)
        self.plan_ids: dict[int, int] = {}
        # mission_type -> the ids a later accepted operation replaced: a MISSION_COUNT naming
        # one of them is answered from a plan the vehicle no longer holds (shared like plan_ids)
        self.replaced_ids: dict[int, set[int]] = {}
        # id(frame) -> (frame, its exchange event), for every received frame an exchange
        # kept; across clauses, since a shared observation's frames decide later clauses too
        self._drawn: dict[int, tuple[Frame, dict[str, Any]]] = {}
        self._sent: tuple[Exchange, dict[str, Any]] | None = None   # the last send's event

    # --- time -----------------------------------------------------------------------------
    def now(self) -> float:
        return self.driver.clock.now()

    def scaled(self, seconds: float) -> float:
        return seconds * self.scale

    @property
    def reply_timeout(self) -> float:
        """The spec's default response timeout (1500 ms), scaled."""
        return self.timings.default_timeout * self.scale

    # --- script ---------------------------------------------------------------------------
    def mark(self) -> None:
        """Ignore everything received so far, including datagrams already waiting in the
        socket (late replies to an earlier exchange must not answer the next one)."""
        self.driver.run_until(_never, timeout=0.0)
        inbox = self.node.inbox
        if len(inbox) > KEEP_FRAMES:   # a chatty target: forget what no expectation can see
            del inbox[: len(inbox) - KEEP_FRAMES // 2]
        self._floor = len(inbox)
        self._consumed.clear()

    @contextlib.contextmanager
    def cooperative(self) -> Iterator[None]:
        """A whole operation done to set up or check state (procedures.py): on a float-only
        target it uses the float forms even in a clause that judges the _INT ones."""
        saved, self.translate = self.translate, True
        try:
            yield
        finally:
            self.translate = saved

    @property
    def float_only(self) -> bool:
        """The _INT forms are sent and waited for as their float twins (float_forms.py)."""
        return not self.int_forms and self.translate

    def send(self, msg: Any) -> None:
        if msg._type in INT_TO_FLOAT and self.float_only:
            if self._told is not self.exchange:
                self._told = self.exchange
                self.note(f"the target answers only the float forms: the tester sends "
                          f"{INT_TO_FLOAT[msg._type]} for {msg._type} (and so on for this clause)")
            msg = to_float(msg)
        mission_type = getattr(msg, "mission_type", None)
        if mission_type is not None:
            self.touched_types.add(mission_type)
        self.node.send(msg)
        self.driver.run_until(_always, timeout=0.0)   # flush it now, and take in what is waiting

    def since_mark(self) -> list[Frame]:
        """Every frame received since the floor, consumed or not (e.g. the STATUSTEXTs that
        give a refusal's reason)."""
        return [frame for _, frame in self.node.inbox[self._floor:]]

    def note(self, text: str) -> int | None:
        """A note in the exchange; its index there (None if no exchange kept it)."""
        if self.exchange is None:
            return None
        return self.exchange.note(self.now(), self.node.name, text)

    # --- what decided the clause ----------------------------------------------------------
    @property
    def decided_by(self) -> int | None:
        """The index in the current exchange of the event that decided the clause so far."""
        return None if self.exchange is None else self.exchange.decided_by

    @decided_by.setter
    def decided_by(self, index: int | None) -> None:
        if self.exchange is not None:
            self.exchange.decide(index)

    def decided_by_frame(self, frame: Frame) -> None:
        """The verdict is about `frame` (received by this tester), not the last frame the
        check consumed. A frame the exchange did not keep leaves no event to mark."""
        if self.exchange is not None:
            drawn = self._drawn.get(id(frame))
            self.exchange.decide(drawn[1] if drawn is not None and drawn[0] is frame else None)

    def _unanswered(self) -> None:
        """A wait got nothing: what decided is the last message this tester sent in this
        clause (a check that knows better says so after). Nothing sent: left as it was."""
        sent = self._sent
        if sent is not None and self.exchange is not None and sent[0] is self.exchange:
            self.exchange.decide(sent[1])

    def _used(self, frame: Frame) -> None:
        """A check consumed `frame`: its exchange event (if one kept it) is evidence."""
        drawn = self._drawn.get(id(frame))
        if drawn is not None and drawn[0] is frame:
            used(drawn[1])

    def _remember(self, frame: Frame, event: dict[str, Any]) -> None:
        drawn = self._drawn
        drawn[id(frame)] = (frame, event)   # holding the frame keeps its id from being reused
        if len(drawn) > KEEP_DRAWN:
            self._drawn = dict(list(drawn.items())[-(KEEP_DRAWN // 2):])

    def expect(self, match: Match, within: float | None = None) -> Frame:
        """The first unconsumed frame since the floor that matches, waiting at most `within`
        seconds (default: the spec's 1500 ms), scaled. Fails the clause if none comes."""
        within = (self.reply_timeout if within is None else within * self.scale) + self.link_allowance
        match = widen(match) if self.float_only else match
        found = self._find(match)
        if found is None:
            self.driver.run_until(self._arrival(match), timeout=within)
            found = self._find(match)
        if found is None:
            self.decided_by = self.note(f"expected {match} within {within:g} s: nothing matching arrived")
            self._check_alive()
            raise ClauseFailed(f"expected {match} within {within:g} s; {self.last_seen()}")
        self.decided_by_frame(found)
        return found

    def poll_for(self, match: Match, within: float, *, forced: bool = False) -> Frame | None:
        """Like `expect`, but None (not a failure) if nothing matching arrives. `forced`:
        the wait's length is set by the target (its stream period, its item timeout), so
        it counts as forced waiting, not as the suite's own time."""
        within = within * self.scale + self.link_allowance
        match = widen(match) if self.float_only else match
        found = self._find(match)
        if found is None:
            started = self.now()
            self.driver.run_until(self._arrival(match), timeout=within)
            found = self._find(match)
            if forced:
                self.forced_wait += self.now() - started
        if found is not None:
            self.decided_by_frame(found)
        else:
            self._unanswered()
        return found

    def wait_until(self, condition: Callable[[], bool], within: float, *, forced: bool = True) -> bool:
        """Run until `condition()` holds or `within` seconds (scaled) pass."""
        started = self.now()
        held = self.driver.run_until(condition, timeout=within * self.scale)
        if forced:
            self.forced_wait += self.now() - started
        return held

    def expect_silence(self, match: Match, for_: float) -> None:
        """Nothing matching may arrive for `for_` seconds (scaled); fails the clause if it does."""
        seen = self.collect(match, for_, stop_at_first=True)
        if seen:
            t, frame = seen[0]
            self.decided_by_frame(frame)
            # the window may follow the target's measured retry interval: both are measured
            raise ClauseFailed(Measured(f"expected no {match} for <window> s; got "
                                        f"{_describe(frame)} after <after> s",
                                        window=f"{for_ * self.scale:g}", after=f"{t:.3f}"))

    def collect(self, match: Match, for_: float, *, stop_at_first: bool = False,
                stop: Match | None = None, quiet: float | None = None) -> list[tuple[float, Frame]]:
        """Every matching frame over a window of `for_` seconds (scaled), as (seconds since
        the window opened, frame). The window closes early at the first frame matching
        `stop` (which is consumed and included), or after `quiet` seconds (scaled) with no
        matching frame once one has come. The window's length counts as forced waiting."""
        start = self.now()
        end = start + for_ * self.scale
        quiet_s = None if quiet is None else quiet * self.scale
        if self.float_only:
            match = widen(match)
            stop = widen(stop) if stop is not None else None
        out: list[tuple[float, Frame]] = []
        cursor = [self._floor]   # frames before it were taken or can never match

        def take() -> bool:
            frames, cursor[0] = self._take_all(match, stop, cursor[0])
            for frame in frames:
                out.append((self.now() - start, frame))
            if out and stop is not None and stop(out[-1][1]):
                return True
            if stop_at_first and out:
                return True
            if quiet_s is not None and out and self.now() - start - out[-1][0] >= quiet_s:
                return True
            return self.now() >= end

        for _ in range(1_000_000):   # each round waits until the next frame or deadline
            if take():
                break
            wake = end if quiet_s is None or not out else min(end, start + out[-1][0] + quiet_s)
            self.driver.run_until(self._arrival(match, stop, cursor[0]), timeout=max(0.0, wake - self.now()))
        self.forced_wait += self.now() - start
        if out:
            self.decided_by_frame(out[-1][1])
        else:
            self._unanswered()
            self._check_alive()
        return out

    # --- internals ------------------------------------------------------------------------
    def _find(self, match: Match, *, peek: bool = False) -> Frame | None:
        inbox, consumed, ours = self.node.inbox, self._consumed, self._ours
        for i in range(self._floor, len(inbox)):
            if i in consumed:
                continue
            frame = inbox[i][1]
            if match(frame) and ours(frame):
                if not peek:
                    consumed.add(i)
                    self._used(frame)
                return frame
        return None

    def _arrival(self, match: Match, stop: Match | None = None,
                 since: int | None = None) -> Callable[[], bool]:
        """A wait's condition: whether an unconsumed frame of ours matching `match` (or
        `stop`) has come since the floor (or `since`). Each call looks only at the frames that
        came after the last call's: one that did not match then never will (a match is a
        test of the frame alone, and nothing is consumed while the driver waits)."""
        node, consumed, ours = self.node, self._consumed, self._ours
        seen = self._floor if since is None else since

        def arrived() -> bool:
            nonlocal seen
            inbox = node.inbox
            for i in range(seen, len(inbox)):
                if i in consumed:
                    continue
                frame = inbox[i][1]
                if ours(frame) and (match(frame) or (stop is not None and stop(frame))):
                    seen = i
                    return True
            seen = len(inbox)
            return False
        return arrived

    def _take_all(self, match: Match, stop: Match | None, since: int) -> tuple[list[Frame], int]:
        """Consume every frame of ours from `since` on that matches `match` (up to and
        including one that matches `stop`); and where the next look may start."""
        out = []
        inbox, consumed = self.node.inbox, self._consumed
        for i in range(since, len(inbox)):
            if i in consumed:
                continue
            frame = inbox[i][1]
            if not self._ours(frame):
                continue
            if match(frame) or (stop is not None and stop(frame)):
                consumed.add(i)
                self._used(frame)
                out.append(frame)
                if stop is not None and stop(frame):
                    return out, i + 1
        return out, len(inbox)

    def _ours(self, frame: Frame) -> bool:
        """Broadcast, or addressed to this tester's system: a reply to another GCS is not ours."""
        return getattr(frame.msg, "target_system", 0) in (0, self.node.endpoint.system)

    def check_alive(self) -> None:
        """Raise TargetUnresponsive if the target has sent nothing for the liveness bound."""
        self._check_alive()

    def _check_alive(self) -> None:
        heard = self.node.last_heard
        if heard is None or self.now() - heard > LIVENESS * self.scale:
            raise TargetUnresponsive(
                "the target sent nothing at all" if heard is None
                else Measured("the target has sent nothing for <silent> s",
                              silent=f"{self.now() - heard:.1f}"))

    def last_seen(self) -> str:
        """The last mission message received since the floor, for a verdict's detail.

        A STATUSTEXT is not one: INAV repeats "UNABLE TO ARM" every few seconds, and naming
        it would hide the protocol message the target last sent (it stays in the exchange)."""
        inbox = self.node.inbox
        for i in range(len(inbox) - 1, self._floor - 1, -1):
            frame = inbox[i][1]
            if relevant(frame.msg._type) and frame.msg._type != "STATUSTEXT":
                return f"last mission message: {_describe(frame)}"
        return "no mission message arrived"


def _always() -> bool:
    return True


def _never() -> bool:
    return False


def _describe(frame: Frame) -> str:
    fields = message_fields(frame.msg)
    shown = ", ".join(f"{k}={v}" for k, v in fields.items()
                      if k not in ("target_system", "target_component"))
    return f"{frame.msg._type}{{{shown}}}"


def record_traffic(tester: Tester) -> None:
    """Route the node's sends and receipts into the tester's current exchange."""
    node = tester.node

    def on_frame(peer: str, now: float, frame: Frame) -> None:
        msg = frame.msg
        if msg._type == "MISSION_ACK" and msg.type == 0:   # MAV_MISSION_ACCEPTED: the plan is new
            ids, replaced = tester.plan_ids, tester.replaced_ids
            new = getattr(msg, "opaque_id", 0)
            for mt in ((0, 1, 2) if msg.mission_type == 255 else (msg.mission_type,)):
                if ids.get(mt) and ids[mt] != new:
                    replaced.setdefault(mt, set()).add(ids[mt])
                ids[mt] = new
        ex = tester.exchange
        if ex is not None and relevant(frame.msg._type):
            index = ex.add(now, "rx", peer, frame.msg._type, message_fields(frame.msg))
            if index is not None:
                tester._remember(frame, ex.events[index])

    def on_send(peer: str, msg: Any) -> None:
        ex = tester.exchange
        index = None if ex is None else ex.add(tester.now(), "tx", peer, msg._type, message_fields(msg))
        tester._sent = None if index is None else (ex, ex.events[index])

    node.on_frame, node.on_send = on_frame, on_send
