"""The GCS side of the Mission Protocol as clauses (MIS.G.*, role gcs).

Half of seed 000 binds the GCS: it starts every operation, drives downloads, owns the
download's timeouts and retries, must resend what got no answer (the last item too, when
the final ACK is lost), must keep the plan types apart, and ends every download with an
ACK. Each sentence that says so is a clause here, with the same rules as the vehicle's
catalogue: the source's own modal word sets the level, ids are stable. The timing clauses
take the spec's recommended values (1500 ms, 5 retries) with the same tolerance the
vehicle's MIS.UP.07 allows: from half to twice the value. The addressing clauses (G.RT) take
seed 001's routing rules, for what the GCS takes as its own, and upstream minimal.xml's
MAV_COMPONENT, for where it sends: the vehicle's component, broadcast (0) being legal but
reaching every component of the vehicle, hence a SHOULD.
"""

from __future__ import annotations

from ..clause import SEED_000, SEED_001, Clause, Level, Role

MUST, SHOULD = Level.MUST, Level.SHOULD
MINIMAL = "mavlink-upstream/minimal.xml"   # MAV_COMPONENT: what a component id is for


def _g(id: str, level: Level, title: str, source: str, requirement: str) -> Clause:
    return Clause(id, level, Role.GCS, title, source, requirement)


_RESEND = ("A timeout is set for every message that requires a response (e.g. MISSION_REQUEST_INT). "
           "If the timeout expires without a response being received then the request must be resent.")
_GIVE_UP = ("If no response is received after a number of retries then the client must cancel the "
            "operation and return to an idle state.")
_INDEPENDENT = ("The protocol uses the same sequence of operations for all types (albeit with different "
                "types of Mission Items). The mission types must be stored and handled separately/independently.")
_DOWNLOAD_ERROR = "An error can be signaled in response to any request using a MISSION_ACK message containing an error code. This must cancel the operation."
_COMPLETE = ("On successful completion, the message must contain type of MAV_MISSION_ACCEPTED; this is "
             "sent by the system that is receiving the command/data (e.g. the drone for mission upload "
             "or the GCS for mission download).")

GCS_CLAUSES: tuple[Clause, ...] = (
    # --- upload ---------------------------------------------------------------------------
    _g("MIS.G.UP.01", MUST, "An upload starts with MISSION_COUNT of the plan's size and type",
       f"{SEED_000}:406", "GCS sends MISSION_COUNT including the number of mission items to be uploaded (count)."),
    _g("MIS.G.UP.02", MUST, "Each MISSION_REQUEST_INT is answered by the MISSION_ITEM_INT it asks for, as planned",
       f"{SEED_000}:414", "GCS receives MISSION_REQUEST_INT and responds with the requested mission item in a "
       "MISSION_ITEM_INT message."),
    _g("MIS.G.UP.03", MUST, "A MISSION_REQUEST (float form) is answered with the item it asks for",
       f"{SEED_000}:434", "The sequence above shows the mission items packaged in MISSION_ITEM_INT messages. "
       "Protocol implementations must also support MISSION_ITEM and MISSION_REQUEST in the same way."),
    _g("MIS.G.UP.04", MUST, "A request the vehicle repeats (its retry) is answered again, the last item's too",
       f"{SEED_000}:428", _RESEND),
    _g("MIS.G.UP.05", MUST, "The last item is resent when the final MISSION_ACK does not come, and the upload then succeeds",
       f"{SEED_000}:428", _RESEND),
    _g("MIS.G.UP.06", MUST, "MISSION_COUNT is resent when the vehicle does not answer it",
       f"{SEED_000}:408", "A timeout must be started for the GCS to wait on the response from Drone "
       "(MISSION_REQUEST_INT)."),
    _g("MIS.G.UP.07", MUST, "A vehicle silent after MISSION_COUNT is given up after the retries: the upload ends as a failure",
       f"{SEED_000}:529", _GIVE_UP),
    _g("MIS.G.UP.08", MUST, "A vehicle's error ACK ends the upload as a failure: no item is sent after it",
       f"{SEED_000}:432", "An error can be signaled in response to any request using a MISSION_ACK message "
       "containing an error code. This must cancel the operation and restore the mission to its previous state."),
    _g("MIS.G.UP.09", SHOULD, "Items go out only when requested, one per request (no flood)",
       f"{SEED_000}:416", "Drone and GCS repeat the MISSION_REQUEST_INT/MISSION_ITEM_INT cycle, iterating seq "
       "until all items are uploaded (seq==count-1)."),
    _g("MIS.G.UP.10", MUST, "An empty plan is uploaded as MISSION_COUNT 0 and succeeds on the vehicle's ACK",
       f"{SEED_000}:436", "Uploading an empty mission (MISSION_COUNT is 0) has the same effect as clearing the mission."),
    # --- download -------------------------------------------------------------------------
    _g("MIS.G.DN.01", MUST, "A download starts with MISSION_REQUEST_LIST of the plan's type",
       f"{SEED_000}:445", "The main difference is that the client (e.g. GCS) sends MISSION_REQUEST_LIST, which "
       "triggers the autopilot to respond with the current count of items."),
    _g("MIS.G.DN.02", MUST, "Items are requested in order, 0 to count-1, and the plan got is the vehicle's",
       f"{SEED_000}:445", "This starts a cycle where the GCS requests mission items, and the drone supplies them."),
    _g("MIS.G.DN.03", MUST, "MISSION_REQUEST_LIST is resent when the vehicle does not answer it",
       f"{SEED_000}:453", _RESEND),
    _g("MIS.G.DN.04", MUST, "An item request is resent when its item does not come",
       f"{SEED_000}:453", _RESEND),
    _g("MIS.G.DN.05", MUST, "A download ends with the GCS's MISSION_ACK ACCEPTED",
       f"{SEED_000}:543", _COMPLETE),
    _g("MIS.G.DN.06", MUST, "A download of an empty plan ends with the GCS's MISSION_ACK ACCEPTED, and succeeds",
       f"{SEED_000}:541", "All operations complete with a MISSION_ACK message containing the result of the "
       "operation (MAV_MISSION_RESULT) in the type field."),
    _g("MIS.G.DN.07", SHOULD, "An out-of-sequence item is dropped and the expected one requested again",
       f"{SEED_000}:455", "Mission items must be received in order. If an item is received out-of-sequence the "
       "expected item should be re-requested by the GCS (the out-of-sequence item is dropped)."),
    _g("MIS.G.DN.08", MUST, "A vehicle's error ACK ends the download as a failure: no request is sent after it",
       f"{SEED_000}:457", _DOWNLOAD_ERROR),
    _g("MIS.G.DN.09", SHOULD, "Items are requested with MISSION_REQUEST_INT",
       f"{SEED_000}:347", "MAVLink users should always prefer MISSION_ITEM_INT because it allows "
       "latitude/longitude to be encoded without the loss of precision that can come from using MISSION ITEM."),
    _g("MIS.G.DN.10", MUST, "A vehicle silent to MISSION_REQUEST_LIST is given up after the retries: the download ends as a failure",
       f"{SEED_000}:529", _GIVE_UP),
    # --- timeouts and retries -----------------------------------------------------------------
    _g("MIS.G.TO.01", SHOULD, "The GCS waits about 1500 ms before resending MISSION_COUNT",
       f"{SEED_000}:533", "Timeout (default): 1500 ms"),
    _g("MIS.G.TO.02", SHOULD, "The GCS resends one message at most 5 times",
       f"{SEED_000}:537", "Retries (max): 5"),
    _g("MIS.G.TO.03", SHOULD, "An upload is kept open through a vehicle's pause as long as the spec's timeouts and retries allow",
       f"{SEED_000}:529", "A timeout should be set for all messages that require a response. If the expected "
       "response is not received before the timeout then the message must be resent. If no response is "
       "received after a number of retries then the client must cancel the operation and return to an idle state."),
    # --- plan types -------------------------------------------------------------------------
    _g("MIS.G.TY.01", MUST, "Fence and rally operations go in MAVLink 2 with their mission_type on every message",
       f"{SEED_000}:273", "Mission protocol messages include the type of associated mission in the mission_type "
       "field (a MAVLink 2 message extension)."),
    _g("MIS.G.TY.02", MUST, "A request for another plan type during an upload is not answered with an item",
       f"{SEED_000}:271", _INDEPENDENT),
    _g("MIS.G.TY.03", MUST, "A MISSION_ACK for another plan type does not end the operation",
       f"{SEED_000}:271", _INDEPENDENT),
    _g("MIS.G.TY.04", MUST, "An item of another plan type during a download is never taken into the plan",
       f"{SEED_000}:271", _INDEPENDENT),
    # --- cancellation -----------------------------------------------------------------------
    _g("MIS.G.CN.01", SHOULD, "A vehicle's OPERATION_CANCELLED ends the operation: nothing more is sent for it",
       f"{SEED_000}:525", "Both systems should then return themselves to the idle state (if the system does not "
       "receive the cancellation message it will resend the request; the recipient will then be in the idle "
       "state and may respond with an appropriate error for that state)."),
    # --- clear ------------------------------------------------------------------------------
    _g("MIS.G.CL.01", MUST, "Clearing sends MISSION_CLEAR_ALL of the plan's type and succeeds on the vehicle's ACK",
       f"{SEED_000}:505", "GCS/API sends MISSION_CLEAR_ALL"),
    _g("MIS.G.CL.02", MUST, "MISSION_CLEAR_ALL is resent when the vehicle does not answer it",
       f"{SEED_000}:517", "A timeout is set for every message that requires a response (e.g. MISSION_CLEAR_ALL). "
       "If the timeout expires without a response being received then the request must be resent."),
    _g("MIS.G.CL.03", MUST, "A vehicle's error ACK ends the clear as a failure",
       f"{SEED_000}:519", "An error can be signaled in response to any request (in this case, just "
       "MISSION_CLEAR_ALL) using a MISSION_ACK message containing an error code. This must cancel the operation."),
    # --- set current ------------------------------------------------------------------------
    _g("MIS.G.SC.01", MUST, "Set-current sends MISSION_SET_CURRENT or MAV_CMD_DO_SET_MISSION_CURRENT with the item",
       f"{SEED_000}:472", "GCS/App sends MISSION SET CURRENT, specifying the new sequence number (seq)."),
    _g("MIS.G.SC.02", SHOULD, "Set-current is not sent again once MISSION_CURRENT has confirmed it",
       f"{SEED_000}:484", "The acknowledgment of the message is via broadcast of mission/system status, which "
       "is not associated with the original message."),
    _g("MIS.G.SC.03", MUST, "Set-current is resent when no MISSION_CURRENT confirms it, and then succeeds",
       f"{SEED_000}:529", "A timeout should be set for all messages that require a response. If the expected "
       "response is not received before the timeout then the message must be resent."),
    # --- addressing (seed 001's routing; the XML's target fields) ---------------------------------
    _g("MIS.G.RT.01", MUST, "A MISSION_ACK addressed to another system is not taken for the GCS's own",
       f"{SEED_001}:96", "The target_system matches its system id and target_component is broadcast "
       "(target_component omitted or zero)."),
    _g("MIS.G.RT.02", MUST, "A MISSION_ACK addressed to another component of the GCS's system, one heard on "
       "the link, is not taken for the GCS's own",
       f"{SEED_001}:97", "The target_system matches its system id and has the component's target_component"),
    _g("MIS.G.RT.03", SHOULD, "Mission messages are addressed to the vehicle's system and component from its "
       "HEARTBEAT, not broadcast",
       f"{MINIMAL}:315", "Component IDs are used for addressing messages to a particular component within a "
       "system. A component can use any unique ID between 1 and 255 (MAV_COMP_ID_ALL value is the broadcast "
       "address, used to send to all components)."),
)

