"""Every bad input raises a clear error naming what is wrong, and the map is unchanged."""

import numpy as np
import pytest

import sndt
from conftest import wall_frame


@pytest.fixture
def mapped():
    """A map with one frame in it, and that frame's arguments."""
    depth, labels, intrinsics, pose = wall_frame()
    m = sndt.Map(cell=0.1, voxels=16384, blocks=2048)
    m.integrate(depth, labels, intrinsics=intrinsics, pose=pose)
    return m, (depth, labels, intrinsics, pose)


def unchanged(m, call, error, *words):
    """`call(m)` raises `error` whose message holds every one of `words`, and `m` keeps its
    snapshot."""
    before = m.snapshot()
    with pytest.raises(error) as e:
        call(m)
    for w in words:
        assert w in str(e.value), (w, str(e.value))
    assert m.snapshot() == before
    return e.value


def test_depth_of_the_wrong_dtype_shape_or_order(mapped):
    m, (depth, labels, k, pose) = mapped
    for bad, err, words in [
        (depth.astype(np.float64), TypeError, ["depth", "float64", "uint16", "float32"]),
        (depth.astype(np.int32), TypeError, ["depth", "int32"]),
        (depth[None], ValueError, ["depth", "shape (N, N)", "(1, 48, 64)"]),
        (np.asfortranarray(depth), ValueError, ["depth", "C-contiguous"]),
        (depth.tolist(), TypeError, ["depth", "numpy array", "list"]),
    ]:
        unchanged(m, lambda m: m.integrate(bad, labels, intrinsics=k, pose=pose), err, *words)
    # A strided view is not C-contiguous either.
    wide = np.zeros((48, 128), dtype=np.float32)[:, ::2]
    unchanged(m, lambda m: m.integrate(wide, labels, intrinsics=k, pose=pose), ValueError, "C-contiguous")


def test_labels_of_the_wrong_dtype_shape_or_class(mapped):
    m, (depth, labels, k, pose) = mapped
    unchanged(m, lambda m: m.integrate(depth, labels.astype(np.int64), intrinsics=k, pose=pose),
              TypeError, "labels", "uint8", "int64")
    unchanged(m, lambda m: m.integrate(depth, labels[:10], intrinsics=k, pose=pose),
              ValueError, "labels", "(48, 64)", "(10, 64)")
    high = labels.copy()
    high[5, 7] = 41
    unchanged(m, lambda m: m.integrate(depth, high, intrinsics=k, pose=pose),
              ValueError, "class 41", "row 5, column 7", "1..=40")
    topk = np.stack([labels, labels])
    unchanged(m, lambda m: m.integrate(depth, topk, intrinsics=k, pose=pose),
              ValueError, "topk_scores")
    scores = np.ones((2, 48, 64), dtype=np.float32)
    unchanged(m, lambda m: m.integrate(depth, topk, intrinsics=k, pose=pose, topk_scores=scores * 2),
              ValueError, "topk_scores", "[0, 1]")
    unchanged(m, lambda m: m.integrate(depth, topk, intrinsics=k, pose=pose,
                                       topk_scores=scores.astype(np.float64)),
              TypeError, "topk_scores", "float64")
    unchanged(m, lambda m: m.integrate(depth, np.stack([labels] * 4), intrinsics=k, pose=pose,
                                       topk_scores=np.ones((4, 48, 64), np.float32)),
              ValueError, "k in 1..=3")
    unchanged(m, lambda m: m.integrate(depth, labels, intrinsics=k, pose=pose, topk_scores=scores),
              ValueError, "topk_scores", "(H, W)")


def test_bad_intrinsics(mapped):
    m, (depth, labels, k, pose) = mapped
    for bad, err, words in [
        ((50.0, 50.0, 32.0), ValueError, ["intrinsics", "four numbers", "got 3"]),
        ((-50.0, 50.0, 32.0, 24.0), ValueError, ["intrinsics", "fx and fy > 0"]),
        ((50.0, float("nan"), 32.0, 24.0), ValueError, ["intrinsics", "finite"]),
        ("fx fy cx cy", TypeError, ["intrinsics"]),
    ]:
        unchanged(m, lambda m: m.integrate(depth, labels, intrinsics=bad, pose=pose), err, *words)


def test_bad_poses(mapped):
    m, (depth, labels, k, pose) = mapped
    nan = np.eye(4)
    nan[0, 3] = np.nan
    sheared = np.eye(4)
    sheared[0, 1] = 0.3
    mirrored = np.diag([1.0, 1.0, -1.0, 1.0])
    last_row = np.eye(4)
    last_row[3, 0] = 1.0
    far = np.eye(4)
    far[0, 3] = 1e6
    unchanged(m, lambda m: m.integrate(depth, labels, intrinsics=k, pose=nan),
              ValueError, "pose", "NaN")
    unchanged(m, lambda m: m.integrate(depth, labels, intrinsics=k, pose=np.eye(3)),
              ValueError, "pose", "(4, 4)", "(3, 3)")
    unchanged(m, lambda m: m.integrate(depth, labels, intrinsics=k, pose=last_row),
              ValueError, "pose", "[0, 0, 0, 1]")
    for rotation in (sheared, mirrored):
        e = unchanged(m, lambda m: m.integrate(depth, labels, intrinsics=k, pose=rotation),
                      sndt.PoseError, "orthonormal")
        assert isinstance(e, sndt.Error)
    unchanged(m, lambda m: m.integrate(depth, labels, intrinsics=k, pose=far),
              sndt.PoseError, "key range")
    unchanged(m, lambda m: m.render(nan, k, 64, 48), ValueError, "pose", "NaN")


def test_bad_depth_values_are_counted_not_raised(mapped):
    """NaN, inf, zero and negative depth are pixels without a measurement (as depth cameras
    report them): counted in the report, every other pixel used."""
    m, (depth, labels, k, pose) = mapped
    d = depth.copy()
    d[0, :4] = [np.nan, np.inf, 0.0, -1.0]
    r = m.integrate(d, labels, intrinsics=k, pose=pose)
    assert r.rejected_depth == 4
    assert r.points_used == d.size - 4


def test_bad_maps(tmp_path):
    with pytest.raises(ValueError, match="classes must be 40"):
        sndt.Map(classes=20)
    with pytest.raises(ValueError, match="voxels=1000, blocks=any.*voxels=1024, blocks=128"):
        sndt.Map(voxels=1000)
    with pytest.raises(sndt.ConfigError, match="cell_size"):
        sndt.Map(cell=-1.0)
    with pytest.raises(sndt.ConfigError, match="max_range / cell_size"):
        sndt.Map(cell=0.001)
    with pytest.raises(TypeError, match="unexpected keyword argument 'celll'.*n_max"):
        sndt.Map(celll=0.1)
    with pytest.raises(ValueError, match="top_k must be an integer in 1..=3, got 300"):
        sndt.Map(top_k=300)
    with pytest.raises(sndt.ConfigError, match="top_k"):
        sndt.Map(top_k=4)
    with pytest.raises(ValueError, match="miss_model must be 'ndt_om' or 'constant'"):
        sndt.Map(miss_model="octomap")
    assert sndt.Map(**{"lambda": 0.2}).config["lambda_"] == pytest.approx(0.2)


def test_corrupt_snapshots(mapped, tmp_path):
    m, _ = mapped
    good = m.snapshot()
    flipped = bytearray(good)
    flipped[len(good) // 2] ^= 0x40
    with pytest.raises(sndt.SnapshotError, match="CRC"):
        sndt.Map.load(bytes(flipped))
    with pytest.raises(sndt.SnapshotError):
        sndt.Map.load(good[: len(good) // 2])
    with pytest.raises(sndt.SnapshotError, match="magic"):
        sndt.Map.load(b"PNG!" + good[4:])
    with pytest.raises(TypeError, match="path"):
        sndt.Map.load(12)
    with pytest.raises(OSError):
        sndt.Map.load(tmp_path / "missing.sndt")
    # A wider wall holds more voxels than the smallest capacity has room for.
    depth, labels, k, pose = wall_frame(h=96, w=128)
    wide = sndt.Map(cell=0.1, voxels=16384, blocks=2048)
    wide.integrate(depth, labels, intrinsics=k, pose=pose)
    assert len(wide) > 1024
    with pytest.raises(sndt.CapacityError):
        sndt.Map.load(wide.snapshot(), voxels=1024)


def test_merges_that_cannot_happen(mapped):
    m, (depth, labels, k, pose) = mapped
    tiny = sndt.Map(cell=0.1, voxels=1024, blocks=128)
    unchanged(tiny, lambda t: t.merge(m), sndt.CapacityError, "merge")
    other = sndt.Map(cell=0.2, voxels=16384, blocks=2048)
    unchanged(m, lambda m: m.merge(other), sndt.ConfigError, "merge")
    unchanged(m, lambda m: m.merge(m), ValueError, "itself")


def test_datasets_that_cannot_be_opened(tmp_path):
    with pytest.raises(sndt.DatasetError):
        sndt.open_dataset(tmp_path / "nothing-here")
    with pytest.raises(sndt.DatasetError, match="synthetic"):
        sndt.open_dataset("synthetic:x:y:z:w")
    with pytest.raises(ValueError, match="every"):
        sndt.open_dataset("synthetic:1:2", every=0)


def test_the_error_classes():
    for e in (sndt.ConfigError, sndt.PoseError, sndt.ImageError, sndt.CapacityError,
              sndt.SnapshotError, sndt.DatasetError):
        assert issubclass(e, sndt.Error) and e.__doc__
    assert issubclass(sndt.Error, Exception)
