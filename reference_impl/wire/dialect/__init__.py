"""mavconform's own MAVLink dialect.

Why we carry our own: the XML bundled with pymavlink (2.4.50) lags upstream MAVLink. It has
no `opaque_id` on MISSION_COUNT / MISSION_ACK, no `mission_id` / `fence_id` /
`rally_points_id` on MISSION_CURRENT, and none of the GCS operator-control definitions
(CONTROL_STATUS, MAV_CMD_REQUEST_OPERATOR_CONTROL, MAV_RESULT_NOT_IN_CONTROL). PX4 speaks
upstream, ArduPilot speaks pymavlink's; the suite must frame and check both. Extensions keep
the two wire-compatible (same ids, same CRC_EXTRA), so this dialect is a superset for the
messages we use, while pymavlink's `dialects.v20.common` stays available for the rest.

`mavconform_dialect.xml` holds only what the suite needs, with upstream's ids, layouts and
values. `mavconform_dialect.py` is generated from it by pymavlink's mavgen and committed:
edit the XML, then run `python -m reference_impl.wire.dialect.regenerate`.
"""

from pathlib import Path

from . import mavconform_dialect as mavlink

XML_PATH: Path = Path(__file__).resolve().parent / "mavconform_dialect.xml"

__all__ = ["XML_PATH", "mavlink"]
