"""Arm primitives as py_trees behaviours (open, close, pick, place, look), with their kinematics
and trajectories. Empty until the arm arrives; see the README's layout."""
