"""Jerk-limited joint trajectories through waypoints, with Ruckig.

Each pair of consecutive waypoints is joined by Ruckig's time-optimal, time-synchronised segment
under the joints' velocity, acceleration and jerk limits; the segments chain into one trajectory
whose position, velocity and acceleration are continuous, which is then sampled at a fixed period
for a position controller.

Stopping at every waypoint is safe but slow along the dense waypoints of a Cartesian path, so by
default the arm passes through intermediate waypoints at speed: a joint that keeps its direction
across a waypoint passes it with its mean velocity over the two neighbouring stop-and-go segments
(a joint that turns back passes at rest), and the acceleration there is zero. A segment in which
some joint would overshoot, going outside the interval between its two waypoints (possibly
beyond a joint limit), gets that joint's passing velocities set to zero, and the segments are
solved again until none overshoots. Ruckig's community edition has no waypoints of its own, hence
this.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from ruckig import InputParameter, Result, Ruckig, RuckigError, Synchronization, Trajectory


@dataclass(frozen=True)
class JointLimits:
    """The limits a trajectory keeps to, joint by joint.

    Args:
        velocity: per-joint maximum |velocity| (rad or m per s).
        acceleration: maximum |acceleration| (per s²).
        jerk: maximum |jerk| (per s³).

    Raises:
        ValueError: an empty or non-positive limit, or lengths that differ.
    """

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    def __post_init__(self) -> None:
        arrays = {name: np.array(getattr(self, name), dtype=float) for name in ("velocity", "acceleration", "jerk")}
        for name, values in arrays.items():
            if values.ndim != 1 or len(values) == 0:
                raise ValueError(f"JointLimits.{name}: expected a non-empty 1-D array, got shape {values.shape}")
            bad = np.flatnonzero(~(np.isfinite(values) & (values > 0)))
            if len(bad):
                raise ValueError(f"JointLimits.{name}[{bad[0]}] = {float(values[bad[0]])!r} "
                                 "is not a positive finite number")
            values.setflags(write=False)
            object.__setattr__(self, name, values)
        lengths = {name: len(values) for name, values in arrays.items()}
        if len(set(lengths.values())) != 1:
            raise ValueError(f"JointLimits: velocity, acceleration and jerk differ in length {lengths}")

    @classmethod
    def uniform(cls, dof: int, velocity: float, acceleration: float, jerk: float) -> JointLimits:
        """The same limits for every joint.

        Args:
            dof: the number of joints.
            velocity: the maximum |velocity|.
            acceleration: the maximum |acceleration|.
            jerk: the maximum |jerk|.

        Returns:
            The limits.
        """
        return cls(np.full(dof, velocity), np.full(dof, acceleration), np.full(dof, jerk))

    @property
    def dof(self) -> int:
        """The number of joints."""
        return len(self.velocity)


@dataclass(frozen=True)
class JointTrajectory:
    """A trajectory sampled every ``dt`` from 0 until the first sample at or after ``duration``.

    Samples after the end hold the last waypoint at rest, so the sample period stays uniform.

    Args:
        times: (m,) the sample times.
        positions: (m, dof) the joint positions at them.
        velocities: (m, dof) the velocities.
        accelerations: (m, dof) the accelerations.
        duration: when the motion ends (s).
        dt: the sample period (s).
        waypoints: (n, dof) the waypoints passed through.
        waypoint_times: (n,) when the trajectory passes each.
        waypoint_velocities: (n, dof) the passing velocities chosen.
        _chain: the segments, which `at` evaluates at any time.
    """

    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    duration: float
    dt: float
    waypoints: np.ndarray
    waypoint_times: np.ndarray
    waypoint_velocities: np.ndarray
    _chain: _Chain = field(repr=False, compare=False)

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The state at any time, between samples too.

        Args:
            t: the time (s), clamped to [0, duration].

        Returns:
            (position, velocity, acceleration), each (dof,).
        """
        return self._chain.state(t)


class _Chain:
    """Ruckig segments laid end to end, each nudged to end exactly on its waypoint.

    Ruckig reaches a target to within ~1e-8; that gap, tiny as it is, would be a position jump
    between segments (a huge jerk in finite differences). Adding (gap / T)·t to a segment of
    duration T closes it, shifting the velocity by gap / T and leaving acceleration and jerk as
    they were.
    """

    def __init__(self, points: np.ndarray, velocities: np.ndarray, segments: list[Trajectory]) -> None:
        self.points, self.velocities, self.segments = points, velocities, segments
        durations = np.array([segment.duration for segment in segments])
        self.starts = np.concatenate([[0.0], np.cumsum(durations)])
        self.duration = float(self.starts[-1])
        self.drifts = np.zeros((len(segments), points.shape[1]))
        for k, segment in enumerate(segments):
            if durations[k] > 0:
                self.drifts[k] = (points[k + 1] - np.array(segment.at_time(durations[k])[0])) / durations[k]

    def state(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        positions, velocities, accelerations = self.sample(np.array([float(t)]))
        return positions[0], velocities[0], accelerations[0]

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities and accelerations (m, dof) at increasing ``times``."""
        dof = self.points.shape[1]
        positions = np.tile(self.points[-1], (len(times), 1))
        velocities = np.zeros((len(times), dof))
        accelerations = np.zeros((len(times), dof))
        inside = np.flatnonzero(times < self.duration)
        clamped = np.maximum(times[inside], 0.0)
        indices = np.minimum(np.searchsorted(self.starts, clamped, side="right") - 1, len(self.segments) - 1)
        local = clamped - self.starts[indices]
        for row, index, t in zip(inside, indices, local, strict=True):
            positions[row], velocities[row], accelerations[row] = self.segments[index].at_time(t)
        drift = self.drifts[indices]
        positions[inside] += drift * local[:, None]
        velocities[inside] += drift
        exact = inside[local == 0.0]  # on a waypoint: exactly there, at the chosen passing velocity
        positions[exact] = self.points[indices[local == 0.0]]
        velocities[exact] = self.velocities[indices[local == 0.0]]
        return positions, velocities, accelerations


def plan_trajectory(waypoints: np.ndarray, limits: JointLimits, dt: float,
                    pass_through: bool = True) -> JointTrajectory:
    """The jerk-limited trajectory through waypoints, starting and ending at rest.

    Args:
        waypoints: (n, dof) joint waypoints.
        limits: the joints' limits.
        dt: the sample period (s).
        pass_through: pass intermediate waypoints at speed (see the module doc); False: stop at
            every waypoint.

    Returns:
        The sampled trajectory.

    Raises:
        ValueError: bad input.
        RuntimeError: Ruckig finds no trajectory.
    """
    points = np.array(waypoints, dtype=float)
    if points.ndim != 2 or len(points) == 0:
        raise ValueError(f"waypoints: expected a non-empty (n, dof) array, got shape {points.shape}")
    if points.shape[1] != limits.dof:
        raise ValueError(f"waypoints: {points.shape[1]} joints, but limits are for {limits.dof}")
    bad = np.argwhere(~np.isfinite(points))
    if len(bad):
        raise ValueError(f"waypoints[{bad[0][0]}, {bad[0][1]}] = {float(points[tuple(bad[0])])!r} is not finite")
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt: {dt!r} is not a positive finite number")

    velocities = np.zeros_like(points)
    segments = _segments_without_overshoot(points, velocities, limits)
    if pass_through and len(points) > 2:
        velocities, segments = _pass_through(points, velocities, segments, limits)
    chain = _Chain(points, velocities, segments)

    count = math.ceil(chain.duration / dt - 1e-9) + 1
    times = np.arange(count) * dt
    positions, speeds, accelerations = chain.sample(times)
    return JointTrajectory(times, positions, speeds, accelerations, chain.duration, dt, points, chain.starts,
                           velocities, chain)


def _pass_through(points: np.ndarray, velocities: np.ndarray, segments: list[Trajectory], limits: JointLimits,
                  rounds: int = 10) -> tuple[np.ndarray, list[Trajectory]]:
    """Raise the passing velocities round by round while the trajectory gets ≥ 1 % shorter.

    Each round sets the velocities from the current segment durations (`_passing_velocities`):
    shorter segments mean faster passes, which shorten the segments again. The first round alone
    brings little on dense waypoints, whose stop-and-go segments are short and slow.
    """
    best = (sum(segment.duration for segment in segments), velocities, segments)
    for _ in range(rounds):
        durations = np.array([segment.duration for segment in best[2]])
        candidate = _passing_velocities(points, durations, limits)
        candidate_segments = _segments_without_overshoot(points, candidate, limits)
        total = sum(segment.duration for segment in candidate_segments)
        improved = total < 0.99 * best[0]
        if total < best[0]:
            best = (total, candidate, candidate_segments)
        if not improved:
            break
    return best[1], best[2]


def _passing_velocities(points: np.ndarray, durations: np.ndarray, limits: JointLimits) -> np.ndarray:
    """Per waypoint and joint: the mean velocity over the two segments around it if the joint keeps
    its direction there, else zero; zero at the first and last waypoints."""
    velocities = np.zeros_like(points)
    before, after = points[1:-1] - points[:-2], points[2:] - points[1:-1]
    span = durations[:-1] + durations[1:]
    safe = np.where(span > 0, span, 1.0)[:, None]
    mean = np.where(span[:, None] > 0, (points[2:] - points[:-2]) / safe, 0.0)
    velocities[1:-1] = np.where(before * after > 0, np.clip(mean, -limits.velocity, limits.velocity), 0.0)
    return velocities


def _segments_without_overshoot(points: np.ndarray, velocities: np.ndarray, limits: JointLimits) -> list[Trajectory]:
    """Solve every segment; zero the passing velocities of joints that overshoot, until none does.

    ``velocities`` is updated in place. Each round zeroes at least one velocity, so it ends.
    """
    while True:
        segments = []
        changed = False
        for k in range(len(points) - 1):
            try:
                segment = _segment(points[k], points[k + 1], velocities[k], velocities[k + 1], limits, k)
            except RuntimeError:
                if not (np.any(velocities[k]) or np.any(velocities[k + 1])):
                    raise
                velocities[k] = velocities[k + 1] = 0.0  # passing at speed failed here: stop instead
                segment = _segment(points[k], points[k + 1], velocities[k], velocities[k + 1], limits, k)
                changed = True
            low, high = np.minimum(points[k], points[k + 1]), np.maximum(points[k], points[k + 1])
            tolerance = 1e-9 * (1.0 + np.abs(points[k]) + np.abs(points[k + 1]))
            for j, extrema in enumerate(segment.position_extrema):
                overshoots = extrema.min < low[j] - tolerance[j] or extrema.max > high[j] + tolerance[j]
                if overshoots and (velocities[k, j] or velocities[k + 1, j]):
                    velocities[k, j] = velocities[k + 1, j] = 0.0
                    changed = True
            segments.append(segment)
        if not changed:
            return segments


def _segment(start: np.ndarray, end: np.ndarray, start_velocity: np.ndarray, end_velocity: np.ndarray,
             limits: JointLimits, index: int) -> Trajectory:
    """Ruckig's time-optimal segment between two states with zero acceleration."""
    dof = limits.dof
    generator = Ruckig(dof)
    request = InputParameter(dof)
    request.current_position = start.tolist()
    request.current_velocity = start_velocity.tolist()
    request.current_acceleration = [0.0] * dof
    request.target_position = end.tolist()
    request.target_velocity = end_velocity.tolist()
    request.target_acceleration = [0.0] * dof
    request.max_velocity = limits.velocity.tolist()
    request.max_acceleration = limits.acceleration.tolist()
    request.max_jerk = limits.jerk.tolist()
    request.synchronization = Synchronization.Phase  # a straight joint-space line where possible
    trajectory = Trajectory(dof)
    try:
        result = generator.calculate(request, trajectory)
    except RuckigError as error:
        raise RuntimeError(f"Ruckig rejected segment {index} (waypoint {index} → {index + 1}): {error}".strip())
    if result not in (Result.Working, Result.Finished):
        raise RuntimeError(f"Ruckig found no trajectory for segment {index} (waypoint {index} → {index + 1}): "
                           f"{result.name}")
    return trajectory
