"""One choice of the profile a target is held to (issue 29): the suite's session, the frame
fuzzer's rig and the protocol fuzzer's world all ask `stored_form.modelling_profile`."""

from mavconform.conformance.harness.stored_form import SPEC_FORM, modelling_profile, stored_form_of
from mavconform.fuzz.protocol.world import profile_for
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.profiles import load_profile

MAV_AUTOPILOT_PX4, MAV_AUTOPILOT_ARDUPILOTMEGA, QUAD, FIXED_WING = 12, 3, 2, 1


def test_the_order_mutant_own_profile_chosen_heartbeat_spec():
    own = load_profile("ardupilot").config
    assert modelling_profile("mutant:x", vehicle_config=own, mutant=True) is None
    assert modelling_profile("builtin:ardupilot", vehicle_config=own, chosen="px4")[0] is own
    chosen, why = modelling_profile("udp:h:1", chosen="px4", autopilot=MAV_AUTOPILOT_ARDUPILOTMEGA)
    assert chosen.autopilot == MAV_AUTOPILOT_PX4 and why == "--profile px4: the px4 profile"
    heard, why = modelling_profile("udp:h:1", autopilot=MAV_AUTOPILOT_ARDUPILOTMEGA, mav_type=FIXED_WING)
    assert heard.behaviour.item_storage == "ardupilot-plane" and why.endswith(": the ardupilot-plane profile")
    assert modelling_profile("udp:h:1", autopilot=0, mav_type=QUAD) is None


def test_every_consumer_gets_the_same_form_and_rules_from_it():
    model = modelling_profile("udp:127.0.0.1:14550", autopilot=MAV_AUTOPILOT_ARDUPILOTMEGA, mav_type=QUAD)
    form = stored_form_of(model)
    assert form.home_at_seq0 and form.storage == "ardupilot"
    rules = profile_for(parse_target("udp:127.0.0.1:14550"), None, autopilot=MAV_AUTOPILOT_ARDUPILOTMEGA,
                        mav_type=QUAD)
    assert rules.form == form and rules.atomic == load_profile("ardupilot").behaviour.atomic_upload is False
    assert stored_form_of(None) == SPEC_FORM
    assert profile_for(parse_target("mutant:non-atomic-upload"), None).form == SPEC_FORM
