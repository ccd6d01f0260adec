"""Frame-fuzz campaigns: Hypothesis draws programs, the rig sends them, the oracle judges.

`search` runs examples in chunks of CHUNK (each chunk a Hypothesis run with its own seed
derived from the campaign's), so a wall-clock budget can end a campaign between chunks and
the same seed and `max_examples` always run the same examples. In-process targets run in
virtual time with a fresh vehicle per example; a failing example is shrunk by Hypothesis,
then `minimise` drops every step and frame the failure does not need (by replaying), and
the result is replayed once more to make sure the saved case reproduces. UDP targets keep
one live target for the campaign: no shrinking (a broken target stays broken), the first
failing example is the case. An interrupt (Ctrl-C) raises `SearchInterrupted` with the
finding being shrunk or minimised, as small as it had become, so it is never lost.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Callable

import hypothesis
from hypothesis import HealthCheck, Phase, Verbosity, given, settings
from hypothesis import strategies as st
from hypothesis.errors import HypothesisException

from mavconform.conformance.target_uri import TargetUri, parse_target
from mavconform.fuzz.case import LINK_LATENCY, Case, Violation, case_latency
from mavconform.fuzz.outcomes import (SearchInterrupted, TargetUnresponsive, ToolError, ToolFailure,
                                      caused_by_interrupt)
from mavconform.fuzz.seeded import seeded_hypothesis
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net.sim import CaptureHook, stable_seed

from .program import FrameSpec, programs
from .rig import Rig

MODE = "frames"
CHUNK = 50                 # examples per Hypothesis run
DEFAULT_EXAMPLES = 200     # when neither max_examples nor stop_after is given
MAX_FRAMES = 400           # frames per example, at most (about 150 on average)
MINIMISE_TRIALS = 300      # replays `minimise` may spend


class _Found(Exception):
    """Raised out of an example to hand Hypothesis a failure; one subclass per invariant, so
    shrinking never trades one broken invariant for another."""

    def __init__(self, violation: Violation, steps: list[dict[str, Any]]) -> None:
        super().__init__(str(violation))
        self.violation = violation
        self.steps = steps


_FOUND: dict[str, type[_Found]] = {}


def _found(violation: Violation, steps: list[dict[str, Any]]) -> _Found:
    cls = _FOUND.get(violation.invariant)
    if cls is None:
        name = "Found_" + "".join(c if c.isalnum() else "_" for c in violation.invariant)
        cls = _FOUND[violation.invariant] = type(name, (_Found,), {})
    return cls(violation, steps)


def setup_step(signing: bool) -> dict[str, Any]:
    return {"setup": {"signing": signing}}


def datagram_step(specs: list[FrameSpec], frames: list[bytes], neutralised: list[int],
                  filled: list[int] = ()) -> dict[str, Any]:
    out = []
    for i, (spec, frame) in enumerate(zip(specs, frames)):
        made = spec.describe()
        if i in filled:
            made += " [replaced by filler: no checksum flip kept the target from accepting it]"
        elif i in neutralised:
            made += " [checksum broken: the target would have accepted it]"
        out.append({"bytes": frame, "made": made})
    return {"send": out}


class FrameCampaign:
    """One campaign against one target; `run()` returns the findings (at most one)."""

    def __init__(self, target: str, *, seed: int, max_examples: int | None = None,
                 stop_after: float | None = None, database: Any = None,
                 on_example: Callable[[int], None] | None = None, transport: str = "auto",
                 max_frames: int = MAX_FRAMES, scale: float = 1.0,
                 capture: CaptureHook | None = None, profile: str | None = None) -> None:
        self.target = target
        self.uri: TargetUri = parse_target(target)
        if transport not in ("auto", "virtual", "udp"):
            raise UsageError(f"bad transport {transport!r} (expected auto, virtual or udp)")
        if transport == "virtual" and not self.uri.in_process:
            raise UsageError(f"target {target}: virtual time needs an in-process target (builtin: or mutant:)")
        self.virtual = self.uri.in_process and transport != "udp"
        if max_examples is None and stop_after is None:
            max_examples = DEFAULT_EXAMPLES
        self.seed = seed
        self.max_examples = max_examples
        self.stop_after = stop_after
        self.database = database
        self.on_example = on_example
        self.max_frames = max_frames
        self.scale = scale            # stretches (or shrinks) the real waits of a UDP campaign
        self.examples = 0
        self.passed_frames = 0        # frames of examples the oracle judged and passed
        self.frames_sent = 0
        self.neutralised = 0
        self.rig: Rig | None = None       # the live target of a UDP campaign
        self.capture = capture            # sees the live traffic of a UDP campaign
        self.profile = profile            # UDP targets: the profile whose stored form downloads are judged in
        self.failure: ToolFailure | None = None   # an exception of ours ended the campaign
        self.pending: Case | None = None          # the finding being shrunk or minimised

    # --- the campaign ---------------------------------------------------------------------
    def run(self) -> list[Case]:
        """The findings (at most one); an interrupt raises `SearchInterrupted` with the one
        being shrunk or minimised, if any, as small as it had become."""
        try:
            return self._run()
        except BaseException as exc:
            if not caused_by_interrupt(exc):
                raise
            pending = self.pending
            raise SearchInterrupted([pending] if pending is not None else [],
                                    phase="search" if pending is None else "shrinking") from None

    def _run(self) -> list[Case]:
        started = time.monotonic()
        try:
            if not self.virtual:
                self.rig = Rig(self.uri, seed=self.seed, virtual=False, scale=self.scale, capture=self.capture,
                               profile=self.profile)
                v = self.rig.start()
                if v is not None:
                    if v.invariant == "target-crash" and self.rig.frames_sent == 0:
                        raise TargetUnresponsive(v.detail)
                    return [self._case([setup_step(False)], v, shrunk=False)]
            chunk = 0
            while self.max_examples is None or self.examples < self.max_examples:
                if self.stop_after is not None and time.monotonic() - started >= self.stop_after:
                    break
                n = CHUNK if self.max_examples is None else min(CHUNK, self.max_examples - self.examples)
                found = self._chunk(chunk, n)
                chunk += 1
                if found is not None:
                    return [found]
            return []
        finally:
            if self.rig is not None:
                self.rig.close()

    def _chunk(self, index: int, n: int) -> Case | None:
        signing = self.uri.kind == "builtin" and self.virtual
        strategy = st.tuples(st.booleans() if signing else st.just(False), programs(self.max_frames))
        phases = [Phase.reuse, Phase.generate] + ([Phase.shrink] if self.virtual else [])
        first: list[_Found] = []
        budget = [n]

        @settings(max_examples=n, database=self.database, deadline=None, phases=phases,
                  suppress_health_check=list(HealthCheck), verbosity=Verbosity.quiet,
                  report_multiple_bugs=False, print_blob=False)
        @hypothesis.seed(stable_seed("frames", self.seed, index))
        @given(strategy)
        def example(drawn: tuple[bool, list[list[FrameSpec]]]) -> None:
            if self.failure is not None:
                return             # the campaign ends: no example runs after a tool failure
            budget[0] -= 1
            signed, program = drawn
            try:
                steps, violation = (self._virtual_example(signed, program) if self.virtual
                                    else self._udp_example(program))
            except Exception as exc:   # noqa: BLE001 - ours, never a finding about the target
                self.failure = ToolFailure.from_exception(exc, [setup_step(signed)], self.seed)
                return
            if violation is not None:
                exc = _found(violation, steps)
                if not first:
                    first.append(exc)
                self._note(violation, steps)
                raise exc

        example._hypothesis_internal_database_key = (  # type: ignore[attr-defined]
            f"mavconform-frames/{self.target}/{self.seed}".encode())
        try:
            with seeded_hypothesis(virtual_time=self.virtual):
                example()
            if self.failure is not None:
                raise ToolError(self.failure)
        except _Found as exc:
            found = exc
        except HypothesisException:
            if not first:
                raise
            found = first[0]        # e.g. a live UDP target that failed once, then not again
        else:
            return None
        if self.virtual:
            return self._finish(found)
        return self._case(found.steps, found.violation, shrunk=False)

    # --- one example ----------------------------------------------------------------------
    def _virtual_example(self, signing: bool, program: list[list[FrameSpec]]) -> tuple[list, Violation | None]:
        rig = Rig(self.uri, seed=self.seed, signing=signing, virtual=True, latency=LINK_LATENCY)
        steps: list[dict[str, Any]] = [setup_step(signing)]
        violation = rig.start()
        if violation is None:
            builder = rig.builder
            for specs in program:
                frames, fixed = builder.datagram(specs)
                rig.send(frames)
                rig.flush()
                steps.append(datagram_step(specs, frames, fixed, builder.admission.last_filled))
                violation = rig.crashed()
                if violation is not None:
                    violation = dataclasses.replace(violation, step=len(steps) - 1)
                    break
            else:
                violation = rig.check()
        self._count(rig, passed=violation is None)
        return steps, violation

    def _udp_example(self, program: list[list[FrameSpec]]) -> tuple[list, Violation | None]:
        rig = self.rig
        builder = rig.builder
        records = []
        for specs in program:
            frames, fixed = builder.datagram(specs)
            rig.send(frames)
            records.append((specs, frames, fixed, list(builder.admission.last_filled)))
        before = rig.frames_sent
        rig.flush()
        violation = rig.crashed() or rig.check(lazy_heartbeat=True)
        self._count(rig, before=before - sum(len(r[1]) for r in records), passed=violation is None)
        steps = [setup_step(False)]
        if violation is not None:
            steps += [datagram_step(*r) for r in records]
        return steps, violation

    def _count(self, rig: Rig, before: int = 0, *, passed: bool) -> None:
        self.examples += 1
        sent = rig.frames_sent - before
        self.frames_sent += sent
        if passed:
            self.passed_frames += sent
        if rig.builder is not None:   # a fresh rig per virtual example, one for a UDP campaign
            n = rig.builder.admission.neutralised
            self.neutralised = self.neutralised + n if self.virtual else n
        if self.on_example is not None:
            self.on_example(sent)

    # --- findings -------------------------------------------------------------------------
    def _note(self, violation: Violation, steps: list[dict[str, Any]]) -> None:
        """Keep the smallest failing example of the first invariant seen: what an interrupt
        saves while Hypothesis shrinks it."""
        old = self.pending
        if old is None or (old.violation is not None and old.violation.invariant == violation.invariant
                           and _frames(steps) < _frames(list(old.steps))):
            self.pending = self._case(steps, violation, shrunk=False)

    def _finish(self, found: _Found) -> Case:
        case = self._case(found.steps, found.violation, shrunk=True)
        self.pending = case
        small = minimise(case)
        again = replay(small)
        if again is None or again.invariant != found.violation.invariant:
            again = replay(case)       # minimising should never lose it; keep the original then
            small = case
        return dataclasses.replace(small, violation=again or found.violation)

    def _case(self, steps: list[dict[str, Any]], violation: Violation, *, shrunk: bool) -> Case:
        return Case(MODE, self.target, self.seed, tuple(steps), violation,
                    {"campaign_seed": self.seed, "examples": self.examples, "frames": self.frames_sent,
                     "transport": "virtual" if self.virtual else "udp", "shrunk": shrunk,
                     **({"latency": LINK_LATENCY} if self.virtual else {})})


def _frames(steps: list[dict[str, Any]]) -> int:
    return sum(len(step.get("send", ())) for step in steps)


def search(target: str, *, seed: int, max_examples: int | None = None, stop_after: float | None = None,
           database: Any = None, on_example: Callable[[int], None] | None = None,
           transport: str = "auto", capture: CaptureHook | None = None,
           profile: str | None = None) -> list[Case]:
    """Fuzz `target` with mutated frames; the shrunk findings (empty: none). `on_example`
    gets the number of frames each example sent. `transport="udp"` runs an in-process
    target over loopback sockets instead of virtual time (the benchmark's setting)."""
    return FrameCampaign(target, seed=seed, max_examples=max_examples, stop_after=stop_after,
                         database=database, on_example=on_example, transport=transport,
                         capture=capture, profile=profile).run()


# --- replay --------------------------------------------------------------------------------

def _parse_steps(case: Case) -> tuple[bool, list[list[bytes]]]:
    signing = False
    datagrams: list[list[bytes]] = []
    for i, step in enumerate(case.steps):
        if "setup" in step:
            setup = step["setup"]
            if i != 0 or not isinstance(setup, dict) or not isinstance(setup.get("signing", False), bool):
                raise UsageError(f"frames case: $.steps[{i}]: 'setup' must be the first step, "
                                 "{signing: true|false}")
            signing = setup.get("signing", False)
            continue
        send = step.get("send")
        if not isinstance(send, list) or not all(
                isinstance(f, dict) and isinstance(f.get("bytes"), bytes) for f in send):
            raise UsageError(f"frames case: $.steps[{i}]: expected {{send: [{{bytes: {{hex: ...}}}}, ...]}}")
        datagrams.append([f["bytes"] for f in send])
    return signing, datagrams


def replay(case: Case, *, capture: CaptureHook | None = None) -> Violation | None:
    """Send the case's datagrams again, in order, to a fresh target (virtual time for
    builtin:/mutant:), then judge it; None if every invariant holds."""
    if case.mode != MODE:
        raise UsageError(f"not a frames case (mode {case.mode!r})")
    uri = parse_target(case.target)
    signing, datagrams = _parse_steps(case)
    if signing and uri.kind != "builtin":
        raise UsageError(f"frames case: a signing vehicle exists only for builtin targets, not {case.target}")
    profile = case.found_by.get("profile")   # the campaign's --profile: the same oracle GCS and stored form
    if profile is not None and not isinstance(profile, str):
        raise UsageError(f"found_by.profile: expected a profile name or file, got {profile!r:.40}")
    rig = Rig(uri, seed=case.seed, signing=signing, virtual=uri.in_process, capture=capture,
              latency=case_latency(case.found_by), profile=profile)
    try:
        violation = rig.start()
        if violation is not None:
            return violation
        offset = 1 if case.steps and "setup" in case.steps[0] else 0
        for i, frames in enumerate(datagrams):
            rig.send(frames)
            rig.flush()
            violation = rig.crashed()
            if violation is not None:
                return dataclasses.replace(violation, step=i + offset)
        return rig.check()
    finally:
        rig.close()


def minimise(case: Case, *, trials: int = MINIMISE_TRIALS) -> Case:
    """The case with every step, then every frame, removed that the failure does not need
    (same invariant on replay); at most `trials` replays. In-process targets only."""
    want = case.violation.invariant if case.violation else None
    if want is None or not parse_target(case.target).in_process:
        return case
    head = [s for s in case.steps if "setup" in s]
    steps = [s for s in case.steps if "setup" not in s]
    left = [trials]

    def fails(candidate: list[dict[str, Any]]) -> bool:
        if left[0] <= 0:
            return False
        left[0] -= 1
        v = replay(dataclasses.replace(case, steps=tuple(head + candidate)))
        return v is not None and v.invariant == want

    size = max(1, len(steps) // 2)
    while size >= 1 and left[0] > 0:        # drop runs of steps, halving the run length
        i = 0
        while i < len(steps) and left[0] > 0:
            candidate = steps[:i] + steps[i + size:]
            if candidate != steps and fails(candidate):
                steps = candidate
            else:
                i += size
        size //= 2
    for si in range(len(steps)):            # then single frames inside the steps left
        frames = steps[si]["send"]
        fi = 0
        while len(frames) > 1 and fi < len(frames) and left[0] > 0:
            trial = frames[:fi] + frames[fi + 1:]
            candidate = steps[:si] + [{"send": trial}] + steps[si + 1:]
            if fails(candidate):
                frames = trial
                steps = candidate
            else:
                fi += 1
    return dataclasses.replace(case, steps=tuple(head + steps))
