"""Recorded motion: readers of joint angles, BVH and C3D markers, and what is done to frames."""
