"""What the API returns, against answers known by hand: a flat wall seen head on."""

import threading

import numpy as np
import pytest

import sndt
from conftest import CELL, wall_frame


def test_a_wall_head_on():
    depth, labels, k, pose = wall_frame(z=2.02, label=7)
    m = sndt.Map(cell=0.1)
    r = m.integrate(depth, labels, intrinsics=k, pose=pose)
    assert isinstance(r, sndt.FrameReport)
    assert r.points_used == depth.size and r.rejected_depth == 0 and r.rejected_label == 0
    assert r.voxels_created == len(m) > 0
    v = m.voxels()
    assert len(v) == len(m)
    assert v.means.shape == (len(m), 3) and v.means.dtype == np.float32
    assert v.covariances.shape == (len(m), 3, 3)
    # Every voxel is on the wall: z = 2.02 within float rounding, class 7 with all votes,
    # flat (no variance along z), occupied.
    np.testing.assert_allclose(v.means[:, 2], 2.02, atol=1e-3)
    assert (v.classes == 7).all() and (v.confidence == 1.0).all()
    np.testing.assert_allclose(v.covariances[:, 2, 2], 0.0, atol=1e-5)
    assert (v.occupancy > 0.5).all()
    np.testing.assert_allclose(v.occupancy, 1 / (1 + np.exp(-v.log_odds)), rtol=1e-6)
    assert v.counts.sum() == depth.size
    # Between the camera and the wall the rays cleared free space; behind it nothing is known.
    states = m.occupancy(np.array([[0.0, 0.0, 2.02], [0.0, 0.0, 1.0], [0.0, 0.0, 3.0]]))
    assert states.tolist() == [sndt.OCCUPIED, sndt.FREE, sndt.UNKNOWN]
    assert m.occupancy(np.zeros((0, 3), np.float32)).shape == (0,)
    # The camera sees the wall it mapped: class 7 across the image, 2.02 m ahead.
    view, dist = m.render(pose, k, 64, 48)
    assert view.shape == (48, 64) and dist.dtype == np.float32
    centre = view[12:36, 16:48]
    assert (centre == 7).all()
    np.testing.assert_allclose(dist[12:36, 16:48], 2.02, atol=CELL / 2)


def test_topk_labels_vote_by_their_best_class_with_top_k_1():
    depth, labels, k, pose = wall_frame()
    ids = np.stack([np.full_like(labels, 3), np.full_like(labels, 5)])
    scores = np.stack([np.full(labels.shape, 0.7, np.float32), np.full(labels.shape, 0.3, np.float32)])
    m = sndt.Map(cell=0.1)
    r = m.integrate(depth, ids, intrinsics=k, pose=pose, topk_scores=scores)
    assert r.points_used == depth.size
    assert (m.voxels().classes == 3).all()
    # With top_k=2 both labels vote: class 5 gets votes too.
    m2 = sndt.Map(cell=0.1, top_k=2)
    m2.integrate(depth, ids, intrinsics=k, pose=pose, topk_scores=scores)
    v = m2.voxels()
    assert (v.classes == 3).all() and (v.confidence < 1.0).all()


def test_config_capacity_and_memory():
    m = sndt.Map(cell=0.05, voxels=4096, blocks=512, n_max=1024, miss_model="constant")
    assert m.capacity == (4096, 512)
    assert m.config["cell_size"] == pytest.approx(0.05)
    assert m.config["n_max"] == 1024 and m.config["miss_model"] == "constant"
    assert set(m.config) == set(sndt.CONFIG_FIELDS) - {"cell"} | {"cell_size"}
    assert m.classes == 40 and len(m) == 0 and m.blocks == 0
    assert m.stats["frames"] == 0
    # 96 bytes per voxel and 192 per block of 4x4x4 cells, plus tables: about 480 KiB, as
    # the firmware's map of this capacity.
    assert 400_000 < m.memory_bytes < 560_000
    assert sndt.Map().capacity == sndt.DEFAULT_CAPACITY == (1 << 19, 1 << 17)
    assert sndt.CAPACITIES[0] == (1024, 128)
    assert "voxels=4096" in repr(m)


def test_merge_of_two_halves_is_their_union():
    """Two maps of disjoint walls merge into the map of both (keys only one side has are
    copied unchanged)."""
    left, right, both = (sndt.Map(cell=0.1, voxels=16384, blocks=2048) for _ in range(3))
    depth, labels, k, _ = wall_frame()
    a, b = np.eye(4), np.eye(4)
    b[0, 3] = 10.0  # ten metres to the side: no voxel in common
    left.integrate(depth, labels, intrinsics=k, pose=a)
    right.integrate(depth, labels, intrinsics=k, pose=b)
    left.merge(right)
    assert len(left) == 2 * len(right)
    assert left.stats["frames"] == 2


def test_two_maps_on_two_threads_at_once(trajectory, python_map):
    """Each thread maps the same frames into its own map while the other runs (the GIL is
    released while a map works); both end as the single-threaded map."""
    _, frames = trajectory
    maps = [sndt.Map(cell=CELL), sndt.Map(cell=CELL)]
    start = threading.Barrier(2)
    errors = []

    def work(m):
        try:
            start.wait()
            for f in frames:
                m.integrate(f.depth, f.labels, intrinsics=f.intrinsics, pose=f.pose)
        except Exception as e:  # noqa: BLE001 - reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(m,)) for m in maps]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    expected = python_map.snapshot()
    assert maps[0].snapshot() == expected and maps[1].snapshot() == expected


def test_one_map_from_two_threads_takes_turns():
    """Calls on one map from two threads take turns: the map ends with every frame."""
    depth, labels, k, pose = wall_frame()
    m = sndt.Map(cell=0.1, voxels=16384, blocks=2048)
    threads = [
        threading.Thread(target=lambda: [m.integrate(depth, labels, intrinsics=k, pose=pose) for _ in range(10)])
        for _ in range(2)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert m.stats["frames"] == 20


def test_datasets_yield_numpy_frames(trajectory):
    traj, frames = trajectory
    assert traj.name.count("/") == 1 and traj.ids[0].startswith(traj.name + "/")
    assert len(traj) == len(frames) == 8
    f = frames[0]
    h, w = f.shape
    assert f.depth.shape == (h, w) and f.depth.dtype == np.float32
    assert f.labels.shape == (h, w) and f.labels.dtype == np.uint8
    assert f.pose.shape == (4, 4) and f.pose.dtype == np.float64
    np.testing.assert_allclose(f.pose[:3, :3] @ f.pose[:3, :3].T, np.eye(3), atol=1e-5)
    assert len(f.intrinsics) == 4 and f.depth_kind in ("planar", "range")
    assert f.id == traj.ids[0] and f.stamp is None
    ids, scores = f.topk
    assert ids.shape == (3, h, w) and scores.dtype == np.float32
    assert len(sndt.open_dataset("synthetic:2:3")) == 2
    assert sndt.open_dataset("synthetic:1:6", every=2).frames == 3


def test_class_names_and_colours():
    assert len(sndt.CLASS_NAMES) == 41 and sndt.CLASS_NAMES[1] == "wall"
    colors = np.array(sndt.CLASS_COLORS, dtype=np.uint8)
    assert colors.shape == (256, 3)
    # The PASCAL-VOC colour map: 1 wall is dark red, 2 floor dark green; 255 dark grey.
    assert colors[1].tolist() == [128, 0, 0] and colors[2].tolist() == [0, 128, 0]
    assert colors[255].tolist() == [40, 40, 40]


def test_every_public_name_has_a_docstring_and_a_stub():
    import pathlib

    stub = (pathlib.Path(sndt.__file__).parent / "_sndt.pyi").read_text()
    assert (pathlib.Path(sndt.__file__).parent / "py.typed").exists()
    for name in sndt.__all__:
        assert name in stub, name
        obj = getattr(sndt, name)
        if callable(obj):
            assert obj.__doc__ and len(obj.__doc__) > 20, name
    classes = (sndt.Map, sndt.Frame, sndt.Trajectory, sndt.Dataset, sndt.Voxels, sndt.FrameReport, sndt.Metrics)
    for cls in classes:
        for attr, value in vars(cls).items():
            if not attr.startswith("_"):
                assert value.__doc__, f"{cls.__name__}.{attr}"
                assert f"def {attr}" in stub or f"{attr}:" in stub, f"{cls.__name__}.{attr}"


@pytest.mark.parametrize("see_through_miss", [0.0, -3.0])
def test_a_wall_that_moves_back(see_through_miss):
    # A wall 2.02 m ahead, at the log-odds clamp (3.5) after six frames, then 1 m farther.
    # With the see-through miss at -3 the rays to the new wall cross the old wall's flat
    # Gaussians and end far behind them: 3.5 - 3 = 0.5 after one frame (still occupied),
    # the lower clamp after two (free). As published (0; the default is -3), NDT-OM's miss
    # is at most -0.41 a frame: occupied after both.
    m = sndt.Map(cell=0.1, see_through_miss=see_through_miss)
    assert m.config["see_through_miss"] == see_through_miss
    old = np.array([[0.0, 0.0, 2.02]])
    for _ in range(6):
        depth, labels, k, pose = wall_frame(z=2.02, label=7)
        m.integrate(depth, labels, intrinsics=k, pose=pose)
    depth, labels, k, pose = wall_frame(z=3.02, label=7)
    m.integrate(depth, labels, intrinsics=k, pose=pose)
    assert m.occupancy(old).tolist() == [sndt.OCCUPIED]
    m.integrate(depth, labels, intrinsics=k, pose=pose)
    moved = sndt.FREE if see_through_miss < 0 else sndt.OCCUPIED
    assert m.occupancy(old).tolist() == [moved]


def test_see_through_miss_is_checked_and_the_dynamic_room_opens():
    assert sndt.Map(cell=0.1).config["see_through_miss"] == -3.0  # the core's default
    with pytest.raises(sndt.ConfigError, match="see_through_miss"):
        sndt.Map(cell=0.1, see_through_miss=-1.4)  # not a multiple of 1/1024
    room = sndt.open_dataset("synthetic:dynamic:111")
    assert len(room) == 1 and room.frames == 111
    with pytest.raises(Exception, match="at least 111"):
        sndt.open_dataset("synthetic:dynamic:100")
    walk = sndt.open_dataset("synthetic:floor-people:1:300")
    assert len(walk) == 1 and walk.frames == 300
    with pytest.raises(Exception, match="give at least"):
        sndt.open_dataset("synthetic:floor-people:1:6")
