"""One check per MSP clause (clauses.py): each writes what its clause is about, reads back,
and fails with the waypoint and field that differ.

What is stored is judged from MSP_WP read-backs (plans.py makes every written waypoint
unlike the record MSP_WP returns for one that does not exist), so only MSP.WP.02-04 lean on
MSP_WP_GETINFO, the command they judge. Every check starts a new mission with number 1,
since that is the only way MSP lets a client put the list in a known state.
"""

from __future__ import annotations

from typing import Callable

from mavconform.reference_impl.msp.commands import FLAG_LAST, Waypoint, waypoint_difference
from mavconform.reference_impl.msp.frame import ERROR, MspFrame, Version, encode

from ..outcome import ClauseFailed, NotApplicable
from .plans import mission, waypoint
from .session import MspSession
from .tester import STORAGE_TIMEOUT, MspTester

MspCheck = Callable[[MspSession], str]
MSP_CHECKS: dict[str, MspCheck] = {}
UNKNOWN_V1, UNKNOWN_V2 = 99, 0x3FFF   # no INAV command has these numbers (an INAV SITL answers `!`)


def check(clause_id: str) -> Callable[[MspCheck], MspCheck]:
    def register(fn: MspCheck) -> MspCheck:
        assert clause_id not in MSP_CHECKS, clause_id
        MSP_CHECKS[clause_id] = fn
        return fn
    return register


def write_ok(t: MspTester, waypoints: list[Waypoint]) -> None:
    """Write them; a `!` to a well-formed waypoint of a known action fails the clause."""
    for wp, reply in zip(waypoints, t.write(waypoints)):
        if reply.direction == ERROR:
            raise ClauseFailed(f"MSP_SET_WP {wp.number} (action {wp.action}) was answered `!`")


def same(t: MspTester, expected: list[Waypoint], what: str) -> None:
    """Each of `expected` reads back as it is, else the clause fails naming the field."""
    for wp in expected:
        back = t.wp(wp.number)
        diff = waypoint_difference(wp, back)
        if diff is not None:
            raise ClauseFailed(f"{what}: waypoint {wp.number}: {diff}")


def absent(t: MspTester, wp: Waypoint, why: str) -> None:
    """`wp` must not read back as written."""
    if t.wp(wp.number) == wp:
        raise ClauseFailed(f"waypoint {wp.number} was stored: {why}")


@check("MSP.WP.01")
def written_reads_back(s: MspSession) -> str:
    t = s.tester
    plan = mission(6)
    write_ok(t, plan)
    same(t, plan, "read back with MSP_WP")
    return f"{len(plan)} waypoints (actions {sorted({wp.action for wp in plan})}) read back field for field"


@check("MSP.WP.02")
def info_counts(s: MspSession) -> str:
    t = s.tester
    steps: list[tuple[str, list[Waypoint], int]] = [
        ("a 4-waypoint mission", mission(4), 4),
        ("a new 2-waypoint mission (number 1 starts it)", mission(2, 1), 2),
    ]
    seen = []
    for what, plan, count in steps:
        write_ok(t, plan)
        info = t.info()
        if info.count != count or not info.valid:
            raise ClauseFailed(f"after {what}: MSP_WP_GETINFO says count {info.count}, valid {int(info.valid)}; "
                               f"the list holds {count}, flagged 0xA5 (valid 1)")
        seen.append(f"{count} after {what}")
    t.set_wp(waypoint(5, 2, last=True))      # a gap: not taken (MSP.WP.07 judges that)
    info = t.info()
    if info.count not in (2, 5):
        raise ClauseFailed(f"after a waypoint 5 written to a 2-waypoint list: MSP_WP_GETINFO says count {info.count}")
    stored = t.wp(5) == waypoint(5, 2, last=True)
    if info.count != (5 if stored else 2):
        raise ClauseFailed(f"waypoint 5 {'was' if stored else 'was not'} stored, yet MSP_WP_GETINFO says count {info.count}")
    return "MSP_WP_GETINFO's count: " + "; ".join(seen) + f"; {info.count} after a waypoint it did not take"


@check("MSP.WP.03")
def flag_ends_mission(s: MspSession) -> str:
    t = s.tester
    plan = mission(3)
    write_ok(t, plan[:2])
    info = t.info()
    if info.valid:
        raise ClauseFailed(f"MSP_WP_GETINFO says the list is valid after waypoints 1-2 of 3, neither flagged 0xA5 "
                           f"(count {info.count})")
    write_ok(t, plan[2:])
    info = t.info()
    if not info.valid:
        raise ClauseFailed("MSP_WP_GETINFO says the list is not valid after waypoint 3, flagged 0xA5")
    flags = [t.wp(n).flag for n in (1, 2, 3)]
    if flags != [0, 0, FLAG_LAST]:
        raise ClauseFailed(f"flags read back {[hex(f) for f in flags]}: expected 0, 0, 0xa5")
    return "not valid after waypoints 1-2 (unflagged), valid once waypoint 3 (0xA5) was taken"


@check("MSP.WP.04")
def maximum_honoured(s: MspSession) -> str:
    t = s.tester
    top = t.info().max_waypoints
    if not 1 <= top <= 253:
        raise ClauseFailed(f"MSP_WP_GETINFO reports a maximum of {top} waypoints (numbers 1..253 are the mission's)")
    plan = mission(top)
    write_ok(t, plan)
    same(t, plan, f"a mission of the reported maximum ({top})")
    extra = waypoint(top + 1, 3, last=True)
    reply = t.set_wp(extra)
    absent(t, extra, f"the reported maximum is {top}")
    how = "refused (`!`)" if reply.direction == ERROR else "ignored (answered `>`, not stored)"
    return f"{top} waypoints stored whole; waypoint {top + 1} {how}"


@check("MSP.WP.05")
def wrong_size_refused(s: MspSession) -> str:
    t = s.tester
    plan = mission(2)
    write_ok(t, plan)
    record = waypoint(1, 4, last=True).pack()
    for size in (20, 22):
        payload = record[:size] if size < 21 else record + b"\x00"
        reply = t.ask("MSP_SET_WP", payload)
        if reply is None:
            raise ClauseFailed(f"MSP_SET_WP with {size} bytes got no reply (a `!` was due)")
        if reply.direction != ERROR:
            raise ClauseFailed(f"MSP_SET_WP with {size} bytes was answered `{reply.direction}`, not `!`")
    same(t, plan, "after MSP_SET_WP payloads of 20 and 22 bytes")
    return "20 and 22 bytes answered `!`; the list unchanged"


@check("MSP.WP.06")
def numbers_outside_not_stored(s: MspSession) -> str:
    t = s.tester
    top = t.info().max_waypoints
    plan = mission(2)
    write_ok(t, plan)
    tried = [0] + [n for n in (top + 1, 200, 253) if top < n <= 253]
    for n in tried:
        t.set_wp(waypoint(n, 5, last=True))
    same(t, plan, f"after MSP_SET_WP {', '.join(map(str, tried))}")
    return f"numbers {', '.join(map(str, tried))} changed nothing in the mission (maximum {top})"


@check("MSP.WP.07")
def only_first_or_next(s: MspSession) -> str:
    t = s.tester
    plan = mission(2)
    write_ok(t, plan)
    gap = waypoint(4, 6, last=True)
    t.set_wp(gap)
    absent(t, gap, "a gap (number 4 after a 2-waypoint list)")
    nxt = waypoint(3, 6, last=True)
    t.set_wp(nxt)
    same(t, plan[:2] + [nxt], "after the next number (3)")
    first = waypoint(1, 7, last=True)
    t.set_wp(first)
    same(t, [first], "after number 1")
    return "number 4 (a gap) not stored; 3 (count + 1) appended; 1 took the list over"


@check("MSP.WP.08")
def no_stale_waypoints(s: MspSession) -> str:
    t = s.tester
    old = mission(5)
    write_ok(t, old)
    new = mission(2, 8)
    write_ok(t, new)
    for wp in old[2:]:
        back = t.wp(wp.number)
        if back == wp:
            raise ClauseFailed(f"MSP_WP {wp.number} read back the older mission's waypoint {wp.number} "
                               "after a 2-waypoint mission replaced it")
    same(t, new, "the new mission")
    return "after a 2-waypoint mission replaced a 5-waypoint one, MSP_WP 3-5 returned none of the old waypoints"


@check("MSP.WP.09")
def save_and_load(s: MspSession) -> str:
    t = s.tester
    loaded = t.ask("MSP_WP_MISSION_LOAD", b"\x00", timeout=STORAGE_TIMEOUT)
    if loaded is None:
        raise ClauseFailed("MSP_WP_MISSION_LOAD got no reply")
    before = t.stored() if loaded.direction != ERROR else None     # what the flight controller had saved
    keep = mission(4, 9)
    write_ok(t, keep)
    saved = t.ask("MSP_WP_MISSION_SAVE", b"\x00", timeout=STORAGE_TIMEOUT)
    if saved is None:
        raise ClauseFailed("MSP_WP_MISSION_SAVE got no reply")
    if saved.direction == ERROR:
        if loaded.direction == ERROR:
            raise NotApplicable("MSP_WP_MISSION_SAVE and _LOAD are answered `!`: no non-volatile waypoint storage")
        raise ClauseFailed("MSP_WP_MISSION_SAVE of a valid 4-waypoint mission was answered `!`")
    write_ok(t, mission(2, 10))
    loaded = t.expect("MSP_WP_MISSION_LOAD", b"\x00", timeout=STORAGE_TIMEOUT)
    if loaded.direction == ERROR:
        raise ClauseFailed("MSP_WP_MISSION_LOAD after a save was answered `!`")
    same(t, keep, "loaded after the save")
    put_back = "none was saved before, so the saved mission is now this clause's"
    if before:
        write_ok(t, before)
        again = t.ask("MSP_WP_MISSION_SAVE", b"\x00", timeout=STORAGE_TIMEOUT)
        put_back = (f"the {len(before)}-waypoint mission saved before was saved again"
                    if again is not None and again.direction != ERROR else "could not save back the mission saved before")
    return f"a 4-waypoint mission saved, overwritten and loaded read back as saved; {put_back}"


@check("MSP.FR.01")
def reply_in_own_framing(s: MspSession) -> str:
    t = s.tester
    answers = {}
    for version in Version:
        reply = t.expect("MSP_WP_GETINFO", version=version)
        if reply.version is not version:
            raise ClauseFailed(f"MSP_WP_GETINFO sent {version.value} was answered in {reply.version.value}")
        answers[version] = reply.payload
    if len(set(answers.values())) != 1:
        raise ClauseFailed(f"the same MSP_WP_GETINFO got different replies by framing: "
                           f"{ {v.value: p.hex() for v, p in answers.items()} }")
    return "MSP_WP_GETINFO answered in v1, v2 and v2 inside v1, as asked, with the same reply"


def _corrupted(frame: MspFrame) -> bytes:
    data = bytearray(encode(frame))
    data[-1] ^= 0xFF
    return bytes(data)


@check("MSP.FR.02")
def bad_checksum_ignored(s: MspSession) -> str:
    t = s.tester
    plan = mission(2)
    write_ok(t, plan)
    intruder = waypoint(1, 11, last=True)
    for version in (Version.V1, Version.V2):
        bad = _corrupted(MspFrame(209, intruder.pack(), version=version))
        reply = t.ask("MSP_SET_WP", raw=bad, timeout=0.5)
        if reply is not None:
            raise ClauseFailed(f"an MSP_SET_WP ({version.value}) with a bad checksum was answered "
                               f"`{reply.direction}`")
    same(t, plan, "after MSP_SET_WP 1 with a bad checksum (v1 XOR, v2 CRC-8)")
    return "MSP_SET_WP 1 with a bad XOR (v1) and CRC-8 (v2): no reply, nothing stored"


@check("MSP.FR.03")
def unknown_command_refused(s: MspSession) -> str:
    t = s.tester
    for code, version in ((UNKNOWN_V1, Version.V1), (UNKNOWN_V2, Version.V2)):
        reply = t.ask(code, version=version)
        if reply is None:
            raise ClauseFailed(f"unknown command {code} ({version.value}) got no reply (a `!` was due)")
        if reply.direction != ERROR:
            raise ClauseFailed(f"unknown command {code} ({version.value}) was answered `{reply.direction}`")
    return f"commands {UNKNOWN_V1} (v1) and {UNKNOWN_V2} (v2) answered `!`"
