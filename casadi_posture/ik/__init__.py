"""Prioritized inverse kinematics: tasks, priority levels, the nullspace and NLP solvers."""
