"""Type stubs of the native module ``sndt._sndt`` (re-exported by ``sndt``)."""

import os
from typing import Any, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

UNKNOWN: int
"""``Map.occupancy`` code: never observed, or outside the map's key range (0)."""
FREE: int
"""``Map.occupancy`` code: log-odds below 0 (1)."""
OCCUPIED: int
"""``Map.occupancy`` code: log-odds above 0 (2)."""
INVALID_LABEL: int
"""The label of a rendered pixel whose ray hits nothing (255)."""
CAPACITIES: List[Tuple[int, int]]
"""The ``(voxels, blocks)`` capacities a ``Map`` can have, smallest first."""
DEFAULT_CAPACITY: Tuple[int, int]
"""The command line's map: ``(2**19, 2**17)``, 74 MiB."""
CLASS_NAMES: List[str]
"""NYU40 class names by id; 0 is ``"void"``."""
CLASS_COLORS: List[Tuple[int, int, int]]
"""RGB colour of each of the 256 label values, as ``sndt``'s pictures draw them (255,
nothing hit, dark grey): ``numpy.array(CLASS_COLORS, dtype=numpy.uint8)[labels]``."""
CONFIG_FIELDS: List[str]
"""The keyword arguments of ``Map`` that set the core's config."""

_Intrinsics = Union[Tuple[float, float, float, float], Sequence[float], npt.NDArray[Any]]
_Pose = Union[npt.NDArray[Any], Sequence[Sequence[float]]]
_Path = Union[str, "os.PathLike[str]"]

class Error(Exception):
    """Base class of every error the map or a dataset reports (argument mistakes are
    TypeError or ValueError)."""

class ConfigError(Error):
    """A config field out of its range, or a merge of maps with different configs."""

class PoseError(Error):
    """A pose whose rotation is not a rotation, or a sensor outside the map's key range."""

class ImageError(Error):
    """An image the map cannot take: sizes that disagree with the camera, or more than
    2^20 points in one frame."""

class CapacityError(Error):
    """The map has no room: a merge or a snapshot needs more voxels or blocks than its
    capacity."""

class SnapshotError(Error):
    """A snapshot that cannot be read: truncated, another format or version, a CRC
    mismatch, or content that breaks the map's invariants."""

class DatasetError(Error):
    """A dataset that cannot be opened or a frame that cannot be read."""

class FrameReport:
    """What one integrated frame did: every pixel is counted once in ``points_used``,
    ``truncated``, ``rejected_*`` or ``dropped_points``."""

    points_used: int
    """Points folded into voxel statistics."""
    truncated: int
    """Points beyond ``max_range``: they only cleared free space up to it."""
    rejected_depth: int
    """Pixels without a measurement: zero, negative, NaN or inf depth."""
    rejected_label: int
    """Points whose labels the map cannot take."""
    rejected_out_of_range: int
    """Points outside the map's key range."""
    dropped_points: int
    """Points lost because the map was full and nothing could be evicted."""
    dropped_misses: int
    """Free-space updates lost for the same reason."""
    end_voxels: int
    """Unique voxels points ended in (one hit update each)."""
    rays: int
    """Rays cast for free space."""
    voxels_created: int
    """Surface voxels created."""
    blocks_created: int
    """Occupancy blocks created."""
    voxels_evicted: int
    """Surface voxels evicted to make room."""
    blocks_evicted: int
    """Occupancy blocks evicted to make room."""
    records_spilled: int
    """Records of evicted voxels and blocks a spill sink took: always 0, as a ``Map`` has
    no sink (its evictions are counted in ``voxels_evicted`` and ``blocks_evicted``)."""
    records_dropped: int
    """Records of evicted voxels and blocks a spill sink refused: always 0, as a ``Map``
    has no sink."""

class Voxels:
    """The surface voxels of a map as arrays, one row per voxel (``Map.voxels()``)."""

    means: npt.NDArray[np.float32]
    """Gaussian means, metres, (N, 3)."""
    covariances: npt.NDArray[np.float32]
    """Gaussian covariances, square metres, (N, 3, 3)."""
    counts: npt.NDArray[np.uint32]
    """Points behind each Gaussian (after decay), (N,)."""
    classes: npt.NDArray[np.uint8]
    """Most voted class, 1..=classes, 0 for a voxel without votes, (N,)."""
    confidence: npt.NDArray[np.float32]
    """Share of the votes the class got, 0 without votes, (N,)."""
    occupancy: npt.NDArray[np.float32]
    """Occupancy probability ``1 / (1 + exp(-log_odds))``, (N,)."""
    log_odds: npt.NDArray[np.float32]
    """Occupancy log-odds, (N,)."""
    def __len__(self) -> int: ...

class Map:
    """A semantic occupancy-NDT map of fixed capacity (it never grows; when full it evicts
    the voxels farthest from the sensor, and the frame report counts them).

    ``cell`` is the voxel edge in metres; ``classes`` the number of classes (40, NYU40:
    ids 1..=40, 0 void); ``voxels`` and ``blocks`` the capacity, one of ``CAPACITIES``
    (default ``DEFAULT_CAPACITY``, the command line's map); ``config`` any field of
    ``CONFIG_FIELDS``, with the core's defaults. The same frames give the same snapshot
    bytes as ``sndt map``.

    Methods release the GIL while the map works, so maps on several threads run in
    parallel; calls on one map from several threads take turns.
    """

    def __init__(
        self,
        cell: float = 0.1,
        classes: int = 40,
        voxels: Optional[int] = None,
        blocks: Optional[int] = None,
        **config: Any,
    ) -> None: ...
    def integrate(
        self,
        depth: Union[npt.NDArray[np.uint16], npt.NDArray[np.float32]],
        labels: Optional[npt.NDArray[np.uint8]] = None,
        *,
        intrinsics: _Intrinsics,
        pose: _Pose,
        topk_scores: Optional[npt.NDArray[np.float32]] = None,
        depth_kind: str = "planar",
        stride: int = 1,
    ) -> FrameReport:
        """Integrates one depth image with its labels, seen from ``pose``.

        ``depth``: ``uint16`` millimetres or ``float32`` metres, (H, W); zero, negative,
        NaN or inf is no measurement. ``labels``: ``uint8`` class ids (H, W), or top-k ids
        (k, H, W) with ``topk_scores`` ``float32`` in [0, 1] of the same shape; ``None`` for
        geometry only. ``intrinsics``: ``(fx, fy, cx, cy)`` in OpenCV's convention (the centre
        of pixel ``(u, v)`` is at ``(u, v)``, as ROS ``CameraInfo.k``). ``pose``: 4x4
        camera-to-world (OpenCV axes). ``depth_kind``: ``"planar"`` or ``"range"``. ``stride``: every
        stride-th pixel in both directions. Raises TypeError/ValueError for a bad argument,
        ``PoseError`` for a pose the map refuses; the map is unchanged then.
        """
    def integrate_frame(self, frame: Frame, labels: str = "gt", stride: int = 1) -> FrameReport:
        """Integrates a dataset frame exactly as ``sndt map`` does, with labels ``"gt"``,
        ``"pred"``, ``"pred_topk"`` or ``"none"``."""
    def render(
        self,
        pose: _Pose,
        intrinsics: _Intrinsics,
        width: int,
        height: int,
        *,
        depth_kind: str = "planar",
    ) -> Tuple[npt.NDArray[np.uint8], npt.NDArray[np.float32]]:
        """What a pinhole camera at ``pose`` sees: ``(labels, depth)``, both (height, width).
        Labels 0 void, 1..=40 class, 255 nothing hit; depth in metres (0 where nothing)."""
    def voxels(self) -> Voxels:
        """The surface voxels as arrays."""
    def occupancy(self, points: npt.NDArray[Any]) -> npt.NDArray[np.uint8]:
        """``UNKNOWN``, ``FREE`` or ``OCCUPIED`` for the voxel of each (N, 3) point."""
    def snapshot(self) -> bytes:
        """The bytes ``sndt map --save-maps`` writes to a ``.sndt`` file."""
    def save(self, path: _Path) -> None:
        """Writes the snapshot to ``path`` atomically."""
    @staticmethod
    def load(
        source: Union[_Path, bytes, bytearray],
        *,
        voxels: Optional[int] = None,
        blocks: Optional[int] = None,
    ) -> Map:
        """A map read from a snapshot file or its bytes (``SnapshotError`` if unreadable,
        ``CapacityError`` if it does not fit)."""
    def merge(self, other: Map) -> None:
        """Adds ``other``'s observations (``ConfigError`` for another config,
        ``CapacityError`` without room; nothing is merged then)."""
    def checksum(self) -> int:
        """CRC-32 of the snapshot."""
    @property
    def config(self) -> Dict[str, Any]:
        """The core's config fields."""
    @property
    def capacity(self) -> Tuple[int, int]:
        """``(voxels, blocks)`` that fit."""
    @property
    def classes(self) -> int:
        """Number of classes (ids 1..=classes; 0 void)."""
    @property
    def memory_bytes(self) -> int:
        """Bytes the map holds (fixed by its capacity)."""
    @property
    def blocks(self) -> int:
        """Occupancy blocks in use."""
    @property
    def stats(self) -> Dict[str, int]:
        """Frames, evicted voxels and blocks, dropped updates since the map was made."""
    def __len__(self) -> int:
        """Surface voxels in the map."""

class Frame:
    """One dataset frame, as numpy values."""

    @property
    def id(self) -> str:
        """``scene/cam/NNNN``."""
    @property
    def shape(self) -> Tuple[int, int]:
        """(height, width)."""
    @property
    def depth(self) -> npt.NDArray[np.float32]:
        """Depth in metres (H, W), of ``depth_kind``."""
    @property
    def depth_kind(self) -> str:
        """``"planar"`` or ``"range"``."""
    @property
    def labels(self) -> Optional[npt.NDArray[np.uint8]]:
        """Ground-truth class ids (H, W), 0 void, or None."""
    @property
    def topk(self) -> Optional[Tuple[npt.NDArray[np.uint8], npt.NDArray[np.float32]]]:
        """Predicted top-3 ids and scores, each (3, H, W), or None."""
    @property
    def intrinsics(self) -> Optional[Tuple[float, float, float, float]]:
        """``(fx, fy, cx, cy)`` in OpenCV's convention, None for a camera with a ray per pixel."""
    @property
    def pose(self) -> npt.NDArray[np.float64]:
        """Camera-to-world 4x4 (OpenCV axes)."""
    @property
    def stamp(self) -> Optional[int]:
        """Recording time, integer nanoseconds (ROS 2 bags), or None."""

class Trajectory:
    """One trajectory (``scene/cam``); iterating reads its frames one at a time."""

    name: str
    @property
    def ids(self) -> List[str]:
        """The frame ids."""
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[Frame]: ...

class Dataset:
    """A dataset opened by ``open_dataset``; iterating yields its trajectories."""

    @property
    def trajectories(self) -> List[Trajectory]:
        """The trajectories, in order."""
    @property
    def frames(self) -> int:
        """Frames over all trajectories."""
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[Trajectory]: ...

class Metrics:
    """mIoU, invR and mPAcc as fractions, with the IoU of each class present."""

    miou: float
    """Mean IoU over the classes present in the ground truth."""
    invr: float
    """Invalid predictions (nothing rendered) over all non-void ground-truth pixels."""
    mpacc: float
    """Mean pixel accuracy over the classes present in the ground truth."""
    per_class_iou: Dict[str, float]
    """IoU per class name, for the classes present in the ground truth."""
    frames: int
    """Frames scored."""

def open_dataset(
    path: _Path,
    *,
    split: Optional[str] = None,
    predictions: Optional[_Path] = None,
    world_frame: Optional[str] = None,
    every: int = 1,
) -> Dataset:
    """Opens what ``sndt map`` takes: a prepared-layout or raw Hypersim directory, a ROS 2
    bag (``.mcap`` file or rosbag2 folder), or ``synthetic[:SCENES:FRAMES]``,
    ``synthetic:floor[:WALK[:FRAMES]]``."""

def evaluate(
    maps: Union[Map, Iterable[Tuple[Map, Iterable[Frame]]]],
    frames: Optional[Iterable[Frame]] = None,
) -> Metrics:
    """The paper's metrics of ``evaluate(map, frames)`` or ``evaluate([(map, frames), ...])``,
    as ``sndt map`` computes them."""
