"""The arm: kinematics (Pinocchio), jerk-limited trajectories (Ruckig), the skill registry
(entry-point group ``homebot.skills``), and the primitives built on them as py_trees behaviours."""
