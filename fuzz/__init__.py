"""Property-based and frame-level fuzzing (see the fuzzing issue)."""
