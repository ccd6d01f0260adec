"""Every clause the suite decides, as data: the vehicle side of the Mission Protocol (MIS.*),
of operator control, the MAVLink layer of authority handover (HO.CTL.*), and of the thesis's
handover procedure carried over it (HO.SEQ.*).

Sources are the seed texts under ../shared/seeds (the Mission Protocol restated in seed
000, framing and routing in seed 001) and the upstream XML where the seed is silent and
upstream speaks (MISSION_CURRENT streaming, opaque_id, MAV_MISSION_TYPE_ALL); operator
control is upstream development.xml's (MAV_CMD_REQUEST_OPERATOR_CONTROL, CONTROL_STATUS); the
handover procedure is the thesis's in seed 003, chapter 4, as docs/handover.md maps it.
Levels follow the source's own words; where a sentence mixes "must" and "should" the
clause takes the word that governs the behaviour checked. Ids are stable: a retired clause keeps its id.
"""

from __future__ import annotations

import fnmatch

from mavconform.reference_impl.errors import UsageError

from .clause import SEED_000, SEED_001, UPSTREAM, Clause, Level, Role

# MAV_CMD_REQUEST_OPERATOR_CONTROL and CONTROL_STATUS (HO.CTL.*) are in the development dialect
DEVELOPMENT = "mavlink-upstream/development.xml"
# the thesis whose authority handover procedure (chapter 4) the HO.SEQ.* clauses check
SEED_003 = "seeds/003_b23246273ffd6472.txt"

MUST, SHOULD, MAY = Level.MUST, Level.SHOULD, Level.MAY
V = Role.VEHICLE


def _c(id: str, level: Level, title: str, source: str, requirement: str) -> Clause:
    return Clause(id, level, V, title, source, requirement)


_UP_SEQ = ("Drone and GCS repeat the MISSION_REQUEST_INT/MISSION_ITEM_INT cycle, iterating seq "
           "until all items are uploaded (seq==count-1).")
_RESEND = ("A timeout is set for every message that requires a response (e.g. MISSION_REQUEST_INT). "
           "If the timeout expires without a response being received then the request must be resent.")
_ERR_RESTORE = ("An error can be signaled in response to any request using a MISSION_ACK message "
                "containing an error code. This must cancel the operation and restore the mission "
                "to its previous state.")
_GIVE_UP = ("If no response is received after a number of retries then the client must cancel "
            "the operation and return to an idle state.")
_BOTH_FORMS = ("Protocol implementations must also support MISSION_ITEM and MISSION_REQUEST in the "
               "same way.")
_INDEPENDENT = "The mission types must be stored and handled separately/independently."
_TYPE_FIELD = ("Mission protocol messages include the type of associated mission in the "
               "mission_type field (a MAVLink 2 message extension).")
_IDLE = ("Both systems should then return themselves to the idle state (if the system does not "
         "receive the cancellation message it will resend the request; the recipient will then "
         "be in the idle state and may respond with an appropriate error for that state).")
_UNALTERED = ("Errors are considered unrecoverable. In an error is sent, both ends of the system "
              "should reset themselves to the idle state and the current state of the mission on "
              "the vehicle should be unaltered.")
_ROBUST = ("Mission update must be robust! A new mission should be fully uploaded and accepted "
           "before the old mission is replaced/removed.")

# Operator control: the vehicle as its own system manager, single-owner mode. Only what the
# XML says the system manager does is a clause; its open choices (a grant's takeover window,
# whether an uncontrolled vehicle takes commands from anyone, which MISSION_ACK code refuses a
# write, how long a silent owner is kept) are not. A sentence without a modal (HO.CTL.09's)
# takes the level of the one it elaborates: 219's "should be rejected".
_STATUS_RATE = ("This should be broadcast at low rate (nominally 1 Hz) and emitted when ownership or "
                "takeover status change.")
_GRANT = ("The system manager component should grant control to the requested GCS(s) if the system "
          "does not require takeover permission (or is uncontrolled) and ACK the request with "
          "MAV_RESULT_ACCEPTED.")

# The thesis's handover procedure (seed 003, ch. 4) over operator control, as docs/handover.md
# maps its six messages to MAV_CMD_REQUEST_OPERATOR_CONTROL traffic (what each clause checks on
# the wire is that mapping: its title names the step). The thesis is a design description: its
# modal words are in 4.1, the application scenario, where 319 says the HO module "must notify
# the GCS-A" on entering the region and, "If communication with the GCS-A is successful", will
# "respond only to the GCS-B". Its procedure sentences (4.3.3, 4.5, 4.6) carry no modal; each
# takes the level of the 4.1 requirement it elaborates, as HO.CTL.09's does: what decides who
# commands (the commander is told, control moves only on its word, then only the new commander
# commands, and a commander that never answers keeps control) elaborates 319: MUST. The means
# toward the partner (the invitation's and the connect notice's form) and the one-handover-per-
# entry rule (docs/handover.md's latch) elaborate no modal sentence: SHOULD.
_WILL_RESPOND = ("If communication with the GCS-A is successful, the HO module will respond only to "
                 "the GCS-B.")

CLAUSES: tuple[Clause, ...] = (
    # --- upload ---------------------------------------------------------------------------
    _c("MIS.UP.01", MUST, "MISSION_COUNT with count > 0 is answered by a request for item 0",
       f"{SEED_000}:410", "Drone receives message and responds with MISSION_REQUEST_INT requesting "
       "the first mission item (seq==0)."),
    _c("MIS.UP.02", MUST, "Items are requested in order, 0 to count-1, one after each item arrives",
       f"{SEED_000}:416", _UP_SEQ),
    _c("MIS.UP.03", MUST, "After the last item the vehicle sends MISSION_ACK ACCEPTED",
       f"{SEED_000}:418", "After receiving the last mission item the drone responds with MISSION_ACK "
       "with the type of MAV_MISSION_ACCEPTED indicating mission upload completion/success."),
    _c("MIS.UP.04", SHOULD, "An accepted upload replaces the stored plan: a download returns the new items",
       f"{SEED_000}:420", "The drone should set the new mission to be the current mission, "
       "discarding the original data."),
    _c("MIS.UP.05", SHOULD, "An abandoned upload leaves the old plan whole",
       f"{SEED_000}:400", _ROBUST),
    _c("MIS.UP.06", MUST, "A requested item that does not arrive is requested again after the item timeout",
       f"{SEED_000}:428", _RESEND),
    _c("MIS.UP.07", SHOULD, "The vehicle's item timeout is about 250 ms",
       f"{SEED_000}:535", "Timeout (mission items): 250 ms."),
    _c("MIS.UP.08", MUST, "After its retries the vehicle gives the upload up and returns to idle",
       f"{SEED_000}:529", _GIVE_UP),
    _c("MIS.UP.09", SHOULD, "The vehicle resends one request at most 5 times",
       f"{SEED_000}:537", "Retries (max): 5"),
    _c("MIS.UP.10", SHOULD, "An item that arrives out of sequence is dropped and the expected one re-requested",
       f"{SEED_000}:430", "Mission items must be received in order. If an item is received "
       "out-of-sequence the expected item should be re-requested by the vehicle (the "
       "out-of-sequence item is dropped)."),
    _c("MIS.UP.11", MUST, "An out-of-sequence item does not end the upload with an error",
       f"{SEED_000}:553", "Out-of-sequence messages in mission upload/download are recoverable, "
       "and are not treated as errors."),
    _c("MIS.UP.12", MUST, "An error ACK from the GCS mid-upload cancels it and keeps the old plan",
       f"{SEED_000}:432", _ERR_RESTORE),
    _c("MIS.UP.13", MUST, "A count the vehicle cannot store is refused with an error ACK and the old plan kept",
       f"{SEED_000}:432", "For example, the drone might respond to the MISSION_COUNT request with a "
       "MAV_MISSION_NO_SPACE if there isn't enough space to upload the mission."),
    _c("MIS.UP.14", MUST, "An upload in MISSION_ITEM (float) messages is accepted like MISSION_ITEM_INT",
       f"{SEED_000}:434", _BOTH_FORMS),
    _c("MIS.UP.15", SHOULD, "The vehicle requests items with MISSION_REQUEST_INT",
       f"{SEED_000}:347", "MAVLink users should always prefer MISSION_ITEM_INT because it allows "
       "latitude/longitude to be encoded without the loss of precision that can come from using "
       "MISSION ITEM."),
    _c("MIS.UP.16", MUST, "An upload with count 0 clears the plan",
       f"{SEED_000}:436", "Uploading an empty mission (MISSION_COUNT is 0) has the same effect as "
       "clearing the mission."),
    _c("MIS.UP.17", SHOULD, "An item the vehicle rejects ends the upload with an error ACK and the old plan kept",
       f"{SEED_000}:547", _UNALTERED),
    # --- download -------------------------------------------------------------------------
    _c("MIS.DN.01", MUST, "MISSION_REQUEST_LIST is answered by MISSION_COUNT with the stored count",
       f"{SEED_000}:445", "The main difference is that the client (e.g. GCS) sends "
       "MISSION_REQUEST_LIST, which triggers the autopilot to respond with the current count of items."),
    _c("MIS.DN.02", MUST, "MISSION_REQUEST_INT k is answered by MISSION_ITEM_INT k holding the stored item",
       f"{SEED_000}:445", "This starts a cycle where the GCS requests mission items, and the drone "
       "supplies them."),
    _c("MIS.DN.03", MUST, "MISSION_REQUEST k (float) is answered by MISSION_ITEM k",
       f"{SEED_000}:460", _BOTH_FORMS),
    _c("MIS.DN.04", MUST, "An empty plan is reported as MISSION_COUNT 0",
       f"{SEED_000}:445", "The main difference is that the client (e.g. GCS) sends "
       "MISSION_REQUEST_LIST, which triggers the autopilot to respond with the current count of items."),
    _c("MIS.DN.05", SHOULD, "A request beyond the list is answered by an error ACK, never an item",
       f"{SEED_000}:457", "An error can be signaled in response to any request using a MISSION_ACK "
       "message containing an error code. This must cancel the operation."),
    _c("MIS.DN.06", MUST, "A repeated request (the GCS's retry) is answered again",
       f"{SEED_000}:453", _RESEND),
    _c("MIS.DN.07", SHOULD, "After the GCS's final ACK the download is over: another GCS is not denied",
       f"{SEED_000}:543", "On successful completion, the message must contain type of "
       "MAV_MISSION_ACCEPTED; this is sent by the system that is receiving the command/data (e.g. "
       "the drone for mission upload or the GCS for mission download)."),
    _c("MIS.DN.08", MUST, "An error ACK from the GCS cancels the download",
       f"{SEED_000}:457", "An error can be signaled in response to any request using a MISSION_ACK "
       "message containing an error code. This must cancel the operation."),
    _c("MIS.DN.09", MUST, "A downloaded item has current=1 exactly when it is the item the vehicle reports current",
       f"{SEED_000}:337", "When downloading, whether the item is the current mission item."),
    # --- clear ----------------------------------------------------------------------------
    _c("MIS.CLR.01", MUST, "MISSION_CLEAR_ALL is answered by MISSION_ACK ACCEPTED",
       f"{SEED_000}:511", "Drone responds with MISSION_ACK with result type of MAV_MISSION_ACCEPTED."),
    _c("MIS.CLR.02", MUST, "After a clear, a download reports count 0",
       f"{SEED_000}:509", "Drone receives the message, and clears the mission from storage."),
    _c("MIS.CLR.03", MUST, "Clearing one plan type leaves the other types",
       f"{SEED_000}:271", _INDEPENDENT),
    _c("MIS.CLR.04", MAY, "MISSION_CLEAR_ALL for MAV_MISSION_TYPE_ALL, when accepted, clears every type",
       f"{UPSTREAM}:3375", "MAV_MISSION_TYPE_ALL: Only used in MISSION_CLEAR_ALL to clear all mission types."),
    _c("MIS.CLR.05", MUST, "A repeated MISSION_CLEAR_ALL (the GCS's retry) is answered again",
       f"{SEED_000}:517", "A timeout is set for every message that requires a response (e.g. "
       "MISSION_CLEAR_ALL). If the timeout expires without a response being received then the "
       "request must be resent."),
    # --- set current ----------------------------------------------------------------------
    _c("MIS.CUR.01", MUST, "A valid MISSION_SET_CURRENT is answered by MISSION_CURRENT with the new seq",
       f"{SEED_000}:476", "On success, the Drone must broadcast a MISSION_CURRENT message "
       "containing the current sequence number (seq)."),
    _c("MIS.CUR.02", MUST, "An invalid MISSION_SET_CURRENT draws a STATUSTEXT",
       f"{SEED_000}:478", "On failure, the Drone must broadcast a STATUSTEXT with a MAV_SEVERITY "
       "and a string stating the problem."),
    _c("MIS.CUR.03", SHOULD, "A failed set-current leaves the current item where it was",
       f"{SEED_000}:474", "Drone receives message and attempts to update the current mission "
       "sequence number."),
    _c("MIS.CUR.04", MUST, "The MISSION_CURRENT after a set-current is broadcast: other GCSs see it",
       f"{SEED_000}:484", "The acknowledgment of the message is via broadcast of mission/system "
       "status, which is not associated with the original message."),
    _c("MIS.CUR.05", SHOULD, "MAV_CMD_DO_SET_MISSION_CURRENT is acknowledged and followed by MISSION_CURRENT",
       f"{UPSTREAM}:1937", "Set the mission item with sequence number seq as the current item and "
       "emit MISSION_CURRENT (whether or not the mission number changed)."),
    _c("MIS.CUR.06", SHOULD, "MISSION_CURRENT is streamed at about 1 Hz",
       f"{UPSTREAM}:5853", "This message should be streamed all the time (nominally at 1Hz)."),
    # --- progress -------------------------------------------------------------------------
    _c("MIS.PRG.01", MUST, "MISSION_ITEM_REACHED is broadcast when an item is reached, with its seq",
       f"{SEED_000}:491", "The vehicle must broadcast a MISSION_ITEM_REACHED message whenever a new "
       "mission item is reached."),
    _c("MIS.PRG.02", MUST, "MISSION_CURRENT is broadcast when the current item changes in flight",
       f"{SEED_000}:493", "The vehicle must also broadcast a MISSION_CURRENT message if the current "
       "mission item is changed."),
    # --- plan types -----------------------------------------------------------------------
    _c("MIS.TYP.01", MUST, "Plan types are stored independently: uploading one leaves the others",
       f"{SEED_000}:271", _INDEPENDENT),
    _c("MIS.TYP.02", MUST, "Upload requests and the final ACK carry the transfer's mission_type",
       f"{SEED_000}:273", _TYPE_FIELD),
    _c("MIS.TYP.03", MUST, "A download reports the requested type's count and items of that mission_type",
       f"{SEED_000}:273", _TYPE_FIELD),
    _c("MIS.TYP.04", SHOULD, "An unknown mission_type is refused with an error ACK, not a transfer",
       f"{SEED_000}:273", "The field takes one of the MAV_MISSION_TYPE enum values."),
    _c("MIS.TYP.05", MUST, "An item of another plan type never becomes part of the running upload",
       f"{SEED_000}:271", _INDEPENDENT),
    # --- several GCSs and addressing ------------------------------------------------------
    _c("MIS.GCS.01", SHOULD, "While one GCS uploads, another GCS's MISSION_COUNT is refused with DENIED",
       f"{UPSTREAM}:3066", "MAV_MISSION_DENIED: Not accepting any mission commands from this "
       "communication partner."),
    _c("MIS.GCS.02", MUST, "Another GCS's traffic does not disturb a running upload",
       f"{SEED_000}:400", _ROBUST),
    _c("MIS.GCS.03", MUST, "Mission messages addressed to another system are not acted on",
       f"{SEED_001}:96", "The target_system matches its system id and target_component is "
       "broadcast (target_component omitted or zero)."),
    _c("MIS.GCS.04", MUST, "Another GCS's MISSION_ACK neither ends nor disturbs a running download",
       f"{SEED_000}:543", "On successful completion, the message must contain type of "
       "MAV_MISSION_ACCEPTED; this is sent by the system that is receiving the command/data (e.g. "
       "the drone for mission upload or the GCS for mission download)."),
    # --- idle, cancellation, errors -------------------------------------------------------
    _c("MIS.IDL.01", MAY, "A stray item or request in idle is ignored or refused, never accepted",
       f"{SEED_000}:525", _IDLE),
    _c("MIS.CAN.01", SHOULD, "OPERATION_CANCELLED from the GCS ends an upload: requests stop",
       f"{SEED_000}:523", "The above mission operations may be canceled by responding to any request "
       "(e.g. MISSION_REQUEST_INT) with a MISSION_ACK message containing the "
       "MAV_MISSION_OPERATION_CANCELLED error."),
    _c("MIS.CAN.02", MUST, "A cancelled upload leaves the stored plan unchanged",
       f"{SEED_000}:432", _ERR_RESTORE),
    _c("MIS.CAN.03", SHOULD, "OPERATION_CANCELLED from the GCS ends a download: the vehicle is idle",
       f"{SEED_000}:525", _IDLE),
    _c("MIS.CAN.04", SHOULD, "After a cancelled upload a new MISSION_COUNT starts afresh from item 0",
       f"{SEED_000}:525", _IDLE),
    _c("MIS.ERR.01", MUST, "Every MISSION_ACK the vehicle sends carries a MAV_MISSION_RESULT value",
       f"{SEED_000}:541", "All operations complete with a MISSION_ACK message containing the result "
       "of the operation (MAV_MISSION_RESULT) in the type field."),
    _c("MIS.ERR.02", SHOULD, "After an error ACK the vehicle is idle: the next operation works",
       f"{SEED_000}:547", _UNALTERED),
    # --- framing --------------------------------------------------------------------------
    _c("MIS.FRM.01", MUST, "Fence and rally transfers are sent in MAVLink 2 frames",
       f"{SEED_000}:273", _TYPE_FIELD),
    _c("MIS.FRM.02", MUST, "Every frame the vehicle sends has a valid checksum (CRC_EXTRA included)",
       f"{SEED_001}:76", "X.25 CRC for message (excluding magic byte). Includes CRC_EXTRA byte."),
    _c("MIS.FRM.03", SHOULD, "The packet sequence number goes up by one with each frame",
       f"{SEED_001}:70", "Used to detect packet loss. Components increment value for each message sent."),
    _c("MIS.FRM.04", MUST, "The vehicle broadcasts HEARTBEAT regularly",
       f"{SEED_001}:149", "Therefore, to set up a connection every component must regularly "
       "broadcast its Heartbeat and monitor for heartbeats from other systems."),
    _c("MIS.FRM.05", MUST, "A frame with a bad checksum, or truncated, is not acted on; the vehicle keeps answering",
       f"{SEED_001}:5", "It provides methods for detecting packet drops, corruption, and for packet "
       "authentication."),
    # --- plan ids -------------------------------------------------------------------------
    _c("MIS.OID.01", MAY, "The opaque_id of the upload ACK comes back in the download's MISSION_COUNT",
       f"{UPSTREAM}:5879", "Id of current on-vehicle mission, fence, or rally point plan (on "
       "download from vehicle)."),
    _c("MIS.OID.02", MAY, "The plan's opaque_id changes when the plan changes",
       f"{UPSTREAM}:5907", "The only requirement on the id is that it must change when there is "
       "any change to the on-vehicle plan type."),
    # --- operator control (development.xml; see _HO below) ---------------------------------
    _c("HO.CTL.01", SHOULD, "CONTROL_STATUS is broadcast at about 1 Hz",
       f"{DEVELOPMENT}:601", _STATUS_RATE),
    _c("HO.CTL.02", SHOULD, "A request for control while no GCS is in control is granted: COMMAND_ACK ACCEPTED",
       f"{DEVELOPMENT}:216", _GRANT),
    _c("HO.CTL.03", SHOULD, "After the owner releases control, CONTROL_STATUS shows no owner and another GCS's "
       "request is granted", f"{DEVELOPMENT}:216", _GRANT),
    _c("HO.CTL.04", SHOULD, "After a grant, the CONTROL_STATUS stream names the new owner in gcs_main",
       f"{DEVELOPMENT}:217", "The system manager component should then stream CONTROL_STATUS indicating "
       "its controlling system(s): all other components in the system (with the same system id) should "
       "monitor this message and set their own controlling GCS(s) to match that of the system manager "
       "component."),
    _c("HO.CTL.05", SHOULD, "CONTROL_STATUS is sent at once when the owner or the takeover flag changes",
       f"{DEVELOPMENT}:601", _STATUS_RATE),
    _c("HO.CTL.06", SHOULD, "Another GCS's request while control is held, takeover not allowed, is refused "
       "with MAV_RESULT_FAILED", f"{DEVELOPMENT}:219", "If the system manager component cannot grant control "
       "because takeover requires permission, the request should be rejected with MAV_RESULT_FAILED."),
    _c("HO.CTL.07", SHOULD, "A request refused for lack of permission is sent on to the owner as the same command",
       f"{DEVELOPMENT}:220", "The system manager component should then send this same command to the "
       "owning GCS with the lowest system ID that has a heartbeat, in order to notify of the request."),
    _c("HO.CTL.08", SHOULD, "Once the owner re-requests with takeover allowed, another GCS's request is granted",
       f"{DEVELOPMENT}:216", _GRANT),
    _c("HO.CTL.09", SHOULD, "Once the owner re-requests with takeover disallowed, requests are refused again",
       f"{DEVELOPMENT}:222", "In case it choses to re-request control with takeover bit set to allow "
       "permission, the requester GCS will only have 10 seconds to get control, otherwise owning GCS will "
       "re-request control with takeover bit set to disallow permission, and requester GCS will need repeat "
       "the request if still interested in getting control."),
    _c("HO.CTL.10", SHOULD, "A command from a GCS not in control is refused: COMMAND_ACK MAV_RESULT_NOT_IN_CONTROL",
       f"{DEVELOPMENT}:204", "Commands to control the vehicle from other systems should be rejected with "
       "MAV_RESULT_NOT_IN_CONTROL (except for this command, which may be acknowledged with "
       "MAV_RESULT_ACCEPTED if control is granted)."),
    _c("HO.CTL.11", SHOULD, "Mission writes from a GCS not in control are refused: the stored plan stays",
       f"{DEVELOPMENT}:203", "A controlled system should only accept MAVLink operations that change the "
       "state of the vehicle, such as commands and command-like messages, which are sent by its controlling "
       "GCS(s) (or from other components in its own system/with the same system id, such as a companion "
       "computer)."),
    _c("HO.CTL.12", MAY, "A GCS not in control may still download the plan and request messages",
       f"{DEVELOPMENT}:205", "Messages and commands that don't control or change vehicle movement or "
       "functionality, such as telemetry requests, may still be send from (and to) a controlled system."),
    _c("HO.CTL.13", SHOULD, "When the owner's HEARTBEATs stop, CONTROL_STATUS comes with no owner",
       f"{DEVELOPMENT}:226", "If all owning GCS are disconnected the vehicle should GCS loss failsafe, and "
       "broadcast a CONTROL_STATUS indicating that it has no owner(s)."),
    # --- the handover sequence (seed 003 ch. 4 over operator control; see _WILL_RESPOND above) ---
    _c("HO.SEQ.01", SHOULD, "On entering the handover region the vehicle invites the partner: "
       "MAV_CMD_REQUEST_OPERATOR_CONTROL to it, param4 = the partner (docs/handover.md step 1)",
       f"{SEED_003}:372", "When the mission computer detects the vehicle flying over the handover region (as "
       "referenced in Chapter 4.6), it initiates the authority handover procedure. This procedure commences "
       "with the drone transmitting a signal to establish a connection with the ground control station to "
       "which authority will be transferred, referred to as \"the partner.\""),
    _c("HO.SEQ.02", MUST, "The partner's request reaches the commander: the vehicle relays it as the same "
       "command, param4 = the partner (docs/handover.md step 2)",
       f"{SEED_003}:319", "Upon entering the handover region, the HO module must notify the GCS-A that it will "
       "transfer the authority over the mission to the GCS-B."),
    _c("HO.SEQ.03", MUST, "Control does not move to the partner before the commander authorises: its "
       "requests are refused and CONTROL_STATUS keeps naming the commander",
       f"{SEED_003}:372", "Following this, the vehicle awaits authorization from the current GCS, known as "
       "\"the commander.\""),
    _c("HO.SEQ.04", MUST, "Once the commander authorises (allows takeover), the partner's request is granted "
       "and CONTROL_STATUS names the partner (docs/handover.md steps 3-4)",
       f"{SEED_003}:374", "Finally, the vehicle disconnects from the current ground control station and "
       "switches to the new commander."),
    _c("HO.SEQ.05", SHOULD, "After the grant the vehicle sends the partner the connect notice: the same "
       "command, param4 = the partner (docs/handover.md step 4)",
       f"{SEED_003}:499", "After receiving the authorization, the drone will send the message "
       "`CONNECT_HANDOVER` to the partner."),
    _c("HO.SEQ.06", MUST, "After the handover only the new commander commands: the old commander's command "
       "gets MAV_RESULT_NOT_IN_CONTROL, the new one's does not",
       f"{SEED_003}:319", _WILL_RESPOND),
    _c("HO.SEQ.07", MUST, "A commander that never authorises keeps control: the handover ends within its bound "
       "without a switch (docs/handover.md, Bound)",
       f"{SEED_003}:319", _WILL_RESPOND),
    _c("HO.SEQ.08", SHOULD, "One handover per entry into the region: while the vehicle stays inside after a "
       "handover, no new invitation (docs/handover.md, hysteresis)",
       f"{SEED_003}:512", "Consequently, when the mission computer detects that the drone has entered this "
       "region, it triggers the authority handover process."),
)

# The GCS's side (MIS.G.*, role gcs): judged by `mavconform run --role gcs`, apart from these.
from .gcs.clauses import GCS_CLAUSES  # noqa: E402
# An MSP flight controller's waypoint store (MSP.*, role msp): `mavconform run --target builtin:msp|msp:...`.
from .msp.clauses import MSP_CLAUSES  # noqa: E402

BY_ID: dict[str, Clause] = {c.id: c for c in CLAUSES + GCS_CLAUSES + MSP_CLAUSES}
assert len(BY_ID) == len(CLAUSES) + len(GCS_CLAUSES) + len(MSP_CLAUSES), "duplicate clause id"
BY_ROLE: dict[Role, tuple[Clause, ...]] = {V: CLAUSES, Role.GCS: GCS_CLAUSES, Role.MSP: MSP_CLAUSES}


def select(globs: str | None = None, levels: str | None = None, role: Role = V) -> list[Clause]:
    """The role's clauses matching any of the comma-separated id globs (case-insensitive)
    and levels. A glob that matches none of them, or an unknown level, is the user's mistake."""
    pool = BY_ROLE[role]
    chosen = list(pool)
    if globs is not None:
        patterns = [g.strip().upper() for g in globs.split(",") if g.strip()]
        if not patterns:
            raise UsageError(f"--clauses {globs!r}: no pattern given")
        for p in patterns:
            if not any(fnmatch.fnmatchcase(c.id, p) for c in pool):
                raise UsageError(f"--clauses: {p!r} matches no {role.value} clause (try `mavconform clauses`)")
        chosen = [c for c in chosen if any(fnmatch.fnmatchcase(c.id, p) for p in patterns)]
    if levels is not None:
        wanted = set()
        for name in (x.strip().upper() for x in levels.split(",") if x.strip()):
            try:
                wanted.add(Level(name))
            except ValueError:
                raise UsageError(f"--level: unknown level {name!r} (MUST, SHOULD or MAY)") from None
        if not wanted:
            raise UsageError(f"--level {levels!r}: no level given (MUST, SHOULD or MAY)")
        chosen = [c for c in chosen if c.level in wanted]
    return chosen
