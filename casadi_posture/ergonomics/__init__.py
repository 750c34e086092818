"""Ergonomic assessments of a posture: whether a task is mirror-symmetric, and how
plausible a posture is for a person (joints near a limit, distance from neutral,
asymmetry, motion out of the task's plane, idle limbs)."""
