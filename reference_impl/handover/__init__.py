"""Authority handover between ground stations: operator control, coverage regions, the mission computer."""
