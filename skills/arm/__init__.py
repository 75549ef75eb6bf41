"""The arm as a pure library: kinematics (Pinocchio), motion planning and jerk-limited trajectories
(Ruckig), grasps, stands and idle spots. It knows nothing of py_trees, Zenoh or the world link, so it
tests with plain arrays; `skills` runs its plans as behaviours.
"""
