"""The 3D map: a truncated signed distance field in an open3d VoxelBlockGrid.

VoxelBlockGrid is used rather than ScalableTSDFVolume because the latter integrates but extracts
nothing in open3d 0.20. Only blocks near observed surfaces are allocated, so the grid stores
surfaces and the truncation band around them; free space far from any surface is read off the 2D
floor instead (see `agent.mapping.occupancy`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d
import open3d.core as o3c

from agent.mapping.camera import Intrinsics

# open3d reports its memory pools at interpreter exit as warnings; they are not problems of ours.
o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)


@dataclass(frozen=True)
class TsdfConfig:
    voxel_size: float = 0.1
    trunc_voxels: float = 5.0
    depth_max: float = 6.0
    block_resolution: int = 8
    block_count: int = 40_000


@dataclass(frozen=True)
class Voxels:
    """Observed voxels: integer lattice indices (N, 3), normalised TSDF in [-1, 1], fusion weights,
    and the voxel size.

    Voxel ``(i, j, k)`` is the TSDF sample at ``(i, j, k) * size`` metres. The indices are what to
    compute with: open3d hands positions back as float32, and a position that should lie on a
    lattice line comes out a hair to either side of it, so flooring it into a coarser grid puts
    neighbouring voxels into one cell and leaves the next cell empty.
    """

    indices: np.ndarray
    tsdf: np.ndarray
    weight: np.ndarray
    size: float

    @property
    def points(self) -> np.ndarray:
        """Positions (N, 3) in metres, exact in float64."""
        return self.indices * self.size


class TsdfMap:
    """Fuses depth frames into a TSDF and hands back the observed voxels as plain arrays.

    Args:
        config: the voxel size, truncation and depth range.
    """

    def __init__(self, config: TsdfConfig = TsdfConfig()) -> None:
        self.config = config
        self._device = o3c.Device("CPU:0")
        self._grid = o3d.t.geometry.VoxelBlockGrid(
            attr_names=("tsdf", "weight"),
            attr_dtypes=(o3c.float32, o3c.float32),
            attr_channels=((1), (1)),
            voxel_size=config.voxel_size,
            block_resolution=config.block_resolution,
            block_count=config.block_count,
            device=self._device,
        )

    def integrate(self, depth: np.ndarray, intrinsics: Intrinsics, camera_to_world: np.ndarray) -> None:
        """Fuse one linear depth image (metres, 0 = no return) seen from ``camera_to_world``.

        Args:
            depth: the depth image.
            intrinsics: the camera's intrinsics.
            camera_to_world: the camera's world pose (4x4).
        """
        image = o3d.t.geometry.Image(o3c.Tensor(np.ascontiguousarray(depth, dtype=np.float32)))
        k = o3c.Tensor(intrinsics.matrix(), dtype=o3c.float64)
        extrinsic = o3c.Tensor(np.linalg.inv(camera_to_world), dtype=o3c.float64)
        cfg = self.config
        blocks = self._grid.compute_unique_block_coordinates(
            image, k, extrinsic, 1.0, cfg.depth_max, cfg.trunc_voxels
        )
        self._grid.integrate(blocks, image, k, extrinsic, 1.0, cfg.depth_max, cfg.trunc_voxels)

    def voxels(self) -> Voxels:
        """Every voxel that some depth ray has updated.

        Returns:
            Their indices, TSDF values and weights.
        """
        coords, indices = self._grid.voxel_coordinates_and_flattened_indices()
        tsdf = self._grid.attribute("tsdf").reshape((-1,))[indices].numpy()
        weight = self._grid.attribute("weight").reshape((-1,))[indices].numpy()
        seen = weight > 0
        indices = np.rint(coords.numpy()[seen] / self.config.voxel_size).astype(np.int64)
        return Voxels(indices, tsdf[seen], weight[seen], self.config.voxel_size)
