"""The reference vehicle as an autopilot (issue 23): vehicle type, modes, arming, flight, home, parameters."""
