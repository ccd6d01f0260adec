"""One shared classification of MAV_TYPE: how a vehicle of that type gets up and down."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.profiles import KNOBS
from mavconform.reference_impl.vehicle_class import VehicleClass, vehicle_class
from mavconform.reference_impl.wire.dialect import mavlink as d


@pytest.mark.parametrize(("mav_type", "expected"), [
    (d.MAV_TYPE_QUADROTOR, VehicleClass.MULTICOPTER), (d.MAV_TYPE_HEXAROTOR, VehicleClass.MULTICOPTER),
    (d.MAV_TYPE_HELICOPTER, VehicleClass.MULTICOPTER), (d.MAV_TYPE_GENERIC_MULTIROTOR, VehicleClass.MULTICOPTER),
    (d.MAV_TYPE_FIXED_WING, VehicleClass.FIXED_WING), (d.MAV_TYPE_FLAPPING_WING, VehicleClass.FIXED_WING),
    (d.MAV_TYPE_VTOL_FIXEDROTOR, VehicleClass.VTOL), (d.MAV_TYPE_VTOL_TAILSITTER_QUADROTOR, VehicleClass.VTOL),
    (d.MAV_TYPE_VTOL_TILTROTOR, VehicleClass.VTOL), (d.MAV_TYPE_GROUND_ROVER, VehicleClass.GROUND),
    (d.MAV_TYPE_SURFACE_BOAT, VehicleClass.GROUND), (d.MAV_TYPE_SUBMARINE, VehicleClass.OTHER),
    (d.MAV_TYPE_AIRSHIP, VehicleClass.OTHER), (d.MAV_TYPE_GCS, VehicleClass.OTHER), (0, VehicleClass.OTHER),
    (255, VehicleClass.OTHER),
])
def test_a_mav_type_has_its_class(mav_type: int, expected: VehicleClass) -> None:
    assert vehicle_class(mav_type) is expected


def test_every_vtol_type_of_common_xml_is_vtol_and_the_values_read_as_words() -> None:
    vtols = [v for v, e in d.enums["MAV_TYPE"].items() if "_VTOL_" in e.name]
    assert len(vtols) >= 7 and all(vehicle_class(v) is VehicleClass.VTOL for v in vtols)
    assert [c.value for c in VehicleClass] == ["multicopter", "fixed-wing", "vtol", "ground", "other"]


def test_the_vehicle_type_knob_takes_a_name_or_a_number() -> None:
    parse = KNOBS["vehicle_type"].parse
    assert parse("FIXED_WING") == parse("MAV_TYPE_FIXED_WING") == parse("fixed_wing") == d.MAV_TYPE_FIXED_WING
    assert parse(22) == d.MAV_TYPE_VTOL_FIXEDROTOR
    for bad in ("JET", 256, -1, True, 1.5):
        with pytest.raises(ValueError, match="MAV_TYPE|whole number"):
            parse(bad)
