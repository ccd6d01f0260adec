"""Golden packet vectors (see the vectors work)."""
