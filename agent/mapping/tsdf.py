"""The 3D map: a truncated signed distance field in an open3d VoxelBlockGrid.

VoxelBlockGrid is used rather than ScalableTSDFVolume because the latter integrates but extracts
nothing in open3d 0.20. Only blocks near observed surfaces are allocated, so the grid stores
surfaces and the truncation band around them; free space far from any surface is read off the 2D
floor instead (see `agent.mapping.occupancy`). A frame updates only the blocks its depth reaches,
and `integrate` says which, so that what is derived from the voxels is renewed there alone rather
than read out of the whole volume every step (`agent.mapping.columns`).
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

    def integrate(self, depth: np.ndarray, intrinsics: Intrinsics, camera_to_world: np.ndarray) -> np.ndarray:
        """Fuse one linear depth image (metres, 0 = no return) seen from ``camera_to_world``.

        Args:
            depth: the depth image.
            intrinsics: the camera's intrinsics.
            camera_to_world: the camera's world pose (4x4).

        Returns:
            The blocks the frame updated, as integer block coordinates (M, 3): no voxel outside
            them changed, so what is derived from the voxels needs renewing only around them.
        """
        cfg = self.config
        if not np.any((depth > 0) & (depth <= cfg.depth_max)):
            return np.zeros((0, 3), dtype=np.int64)  # open3d refuses a frame that reaches no block
        image = o3d.t.geometry.Image(o3c.Tensor(np.ascontiguousarray(depth, dtype=np.float32)))
        k = o3c.Tensor(intrinsics.matrix(), dtype=o3c.float64)
        extrinsic = o3c.Tensor(np.linalg.inv(camera_to_world), dtype=o3c.float64)
        blocks = self._grid.compute_unique_block_coordinates(
            image, k, extrinsic, 1.0, cfg.depth_max, cfg.trunc_voxels
        )
        self._grid.integrate(blocks, image, k, extrinsic, 1.0, cfg.depth_max, cfg.trunc_voxels)
        return blocks.numpy().astype(np.int64).reshape(-1, 3)

    def blocks(self) -> np.ndarray:
        """Every allocated block's integer coordinates (N, 3); block ``b`` holds the voxels
        ``b * block_resolution + (0..block_resolution-1)`` along each axis.

        Returns:
            The block coordinates.
        """
        hashmap = self._grid.hashmap()
        return hashmap.key_tensor()[hashmap.active_buf_indices()].numpy().astype(np.int64).reshape(-1, 3)

    def fields(self, blocks: np.ndarray) -> np.ndarray:
        """The normalised TSDF of some allocated blocks, for reading a part of the map cheaply.

        Args:
            blocks: integer block coordinates (M, 3), as `blocks` or `integrate` give them.

        Returns:
            The values (M, R, R, R) indexed ``[block, x, y, z]`` (R the block resolution), NaN
            where no depth ray has reached the voxel.
        """
        resolution = self.config.block_resolution
        blocks = np.asarray(blocks, dtype=np.int64).reshape(-1, 3)
        if len(blocks) == 0:
            return np.zeros((0, resolution, resolution, resolution), dtype=np.float32)
        found, _ = self._grid.hashmap().find(o3c.Tensor(blocks.astype(np.int32)))
        rows = found.numpy().astype(np.int64)
        shape = (-1, resolution, resolution, resolution)
        tsdf = self._grid.attribute("tsdf").numpy().reshape(shape)[rows]
        weight = self._grid.attribute("weight").numpy().reshape(shape)[rows]
        # open3d lays a block's voxels out as [z, y, x]
        return np.where(weight > 0, tsdf, np.float32(np.nan)).transpose(0, 3, 2, 1)
