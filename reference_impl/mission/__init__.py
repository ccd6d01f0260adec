"""Mission Protocol: items, stores, and the sans-IO server (vehicle) and client (GCS) engines."""
