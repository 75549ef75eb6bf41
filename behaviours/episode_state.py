"""What the act branch's leaves remember over an episode, kept on the blackboard (not in the
leaves) so that a leaf holds only its settings and its work in progress.

`ActRecord` is one try to open a door or drawer and look inside (the blackboard's ``acts``, the
episode record's ``acts``); `ApproachState` is what `behaviours.approach_storage.ApproachStorage`
has seen and tried; `LookInsideState` is what `behaviours.look_inside.LookInside` has seen and
opened.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from agent.observation import Observation
from agent.perception.memory import InstanceMemory, MemoryConfig
from agent.perception.sightings import Sightings
from agent.planning.room_goal import RoomFloors
from skills.skill_runs import SkillRuns

#: Parts attach to the part or piece with voxels this near (`MemoryConfig.part_gap_m`): a little
#: more than the memory's default, since storage is often first seen from metres away, where a
#: handle's few voxels lie further off its door.
PART_GAP_M = 0.07


@dataclass
class ActRecord:
    """One try to open a door or drawer of storage and look inside: what was tried (``storage``,
    ``part``), where the piece stands (``piece_xy``), how far it opened (in ``unit``, opening_deg
    or opening_m), whether the frames went to the VLM (``looked``) and at which ``step``, whether it
    was closed again, and at which ``stage`` and why (``reason``) it failed."""

    storage: str
    part: str
    piece_xy: list[float]
    unit: str
    opening: float = 0.0
    opened: bool = False
    looked: bool = False
    closed: bool | None = None
    stage: str | None = None
    reason: str = ""
    outcome: str = ""
    seconds: float = 0.0
    step: int | None = None

    def fail(self, stage: str, reason: str) -> None:
        """Record the first failure; later ones leave it as it is.

        Args:
            stage: look, open, close or stow.
            reason: why.
        """
        if not self.stage:
            self.stage, self.reason = stage, reason

    def to_record(self) -> dict[str, Any]:
        """The act as the episode's record keeps it.

        Returns:
            The record's fields, in the record's order (``step`` only once the VLM looked).
        """
        record: dict[str, Any] = {"storage": self.storage, "part": self.part, "piece_xy": self.piece_xy,
                                  "opened": self.opened, self.unit: self.opening, "looked": self.looked,
                                  "closed": self.closed, "stage": self.stage, "reason": self.reason,
                                  "outcome": self.outcome, "seconds": self.seconds}
        if self.step is not None:
            record["step"] = self.step
        return record


@dataclass
class PieceProgress:
    """How far the approach to one piece seen has gone: the bearings of the viewpoints driven to
    and the moves made towards it."""

    tried: list[float] = field(default_factory=list)
    moves: int = 0


@dataclass
class ApproachState:
    """What `ApproachStorage` has seen and done this episode: the pieces of the named kind seen
    (``sightings``, made on the first frame) with the ``progress`` towards each, the floor seen of
    each room kind, the moves made into the named room, whether the robot has stood in it, and
    the last frame taken in (``seen``)."""

    sightings: Sightings | None = None
    progress: list[PieceProgress] = field(default_factory=list)  # by index into sightings.pieces
    floors: RoomFloors | None = None
    room_moves: int = 0
    entered: bool = False
    seen: Observation | None = None


@dataclass
class LookInsideState:
    """What `LookInside` has seen and opened this episode: the instance memory of the frames, the
    room kind a frame showed each storage piece in (by memory id), the floor seen of each room
    kind (once the map is known), and the parts tried."""

    memory: InstanceMemory = field(default_factory=lambda: InstanceMemory(MemoryConfig(part_gap_m=PART_GAP_M)))
    rooms: dict[int, str] = field(default_factory=dict)
    floors: RoomFloors | None = None
    tried: set[int] = field(default_factory=set)
    arm: SkillRuns = field(default_factory=SkillRuns)  # every skill the acts ran, for a recording
