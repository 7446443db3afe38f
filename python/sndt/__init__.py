"""Semantic occupancy-NDT maps (S-NDT) from numpy arrays.

A map keeps, per voxel, a Gaussian of the points that fell in it, an occupancy value with
free space from ray casting, and a histogram of the classes a segmentation network gave
those points. Feed it depth images with labels, render semantic views back out, and score
them with the evaluation of Seichter et al. (ICRA 2022), the same bits as the ``sndt``
command line.

>>> import numpy as np, sndt
>>> m = sndt.Map(cell=0.1)
>>> depth = np.full((48, 64), 2.0, dtype=np.float32)      # a wall 2 m ahead
>>> labels = np.full((48, 64), 1, dtype=np.uint8)          # class 1, "wall"
>>> report = m.integrate(depth, labels, intrinsics=(50.0, 50.0, 32.0, 24.0), pose=np.eye(4))
>>> report.points_used
3072
>>> view, dist = m.render(np.eye(4), (50.0, 50.0, 32.0, 24.0), 64, 48)
>>> int(view[24, 32]), round(float(dist[24, 32]), 1)
(1, 2.0)
"""

from ._sndt import (
    CAPACITIES,
    CLASS_COLORS,
    CLASS_NAMES,
    CONFIG_FIELDS,
    DEFAULT_CAPACITY,
    FREE,
    INVALID_LABEL,
    OCCUPIED,
    UNKNOWN,
    CapacityError,
    ConfigError,
    Dataset,
    DatasetError,
    Error,
    Frame,
    FrameReport,
    ImageError,
    Map,
    Metrics,
    PoseError,
    SnapshotError,
    Trajectory,
    Voxels,
    __version__,
    evaluate,
    open_dataset,
)

__all__ = [
    "CAPACITIES",
    "CLASS_COLORS",
    "CLASS_NAMES",
    "CONFIG_FIELDS",
    "DEFAULT_CAPACITY",
    "FREE",
    "INVALID_LABEL",
    "OCCUPIED",
    "UNKNOWN",
    "CapacityError",
    "ConfigError",
    "Dataset",
    "DatasetError",
    "Error",
    "Frame",
    "FrameReport",
    "ImageError",
    "Map",
    "Metrics",
    "PoseError",
    "SnapshotError",
    "Trajectory",
    "Voxels",
    "__version__",
    "evaluate",
    "open_dataset",
]
