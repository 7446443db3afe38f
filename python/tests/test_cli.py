"""The map from Python is the command line's map: same snapshot bytes, same renders, same
metrics, on the same frames."""

import zlib

import numpy as np
import png
import pytest

import sndt
from conftest import CELL


def read_png(path):
    """A plain 8-bit grey PNG (the back-projection layout) as a uint8 (H, W) array."""
    w, h, rows, info = png.Reader(filename=str(path)).read()
    assert info["bitdepth"] == 8 and info["planes"] == 1
    return np.array([np.frombuffer(bytes(r), dtype=np.uint8) for r in rows]).reshape(h, w)


def test_snapshot_is_the_command_lines_byte_for_byte(python_map, cli_run):
    ours = python_map.snapshot()
    assert len(ours) == len(cli_run["snapshot"])
    assert ours == cli_run["snapshot"]
    # The snapshot ends in the CRC-32 of what comes before it, little-endian (as zlib
    # computes it): the same number checksum() reports.
    assert python_map.checksum() == int.from_bytes(ours[-4:], "little")
    assert zlib.crc32(ours[:-4]) == python_map.checksum()


def test_integrate_frame_takes_the_command_lines_path(trajectory, python_map):
    _, frames = trajectory
    m = sndt.Map(cell=CELL)
    for f in frames:
        m.integrate_frame(f, "gt")
    assert m.snapshot() == python_map.snapshot()


def test_millimetre_depth_is_the_metre_depth_it_stands_for(trajectory):
    """uint16 millimetres v are v / 1000 metres: a map from depth rounded to whole
    millimetres equals the map from those millimetres as float32 metres."""
    _, frames = trajectory
    mm_map, m_map = sndt.Map(cell=CELL), sndt.Map(cell=CELL)
    for f in frames[:3]:
        mm = np.nan_to_num(f.depth * 1000.0, nan=0.0, posinf=0.0).round().clip(0, 65535)
        mm = mm.astype(np.uint16)
        metres = mm.astype(np.float32) / np.float32(1000.0)
        a = mm_map.integrate(mm, f.labels, intrinsics=f.intrinsics, pose=f.pose)
        b = m_map.integrate(metres, f.labels, intrinsics=f.intrinsics, pose=f.pose)
        assert (a.points_used, a.rejected_depth) == (b.points_used, b.rejected_depth)
        assert a.points_used > 0
    assert mm_map.snapshot() == m_map.snapshot()


def test_render_is_the_command_lines_back_projection(python_map, trajectory, cli_run):
    _, frames = trajectory
    for f in frames:
        h, w = f.shape
        labels, depth = python_map.render(f.pose, f.intrinsics, w, h)
        scene, cam, index = f.id.split("/")
        expected = read_png(cli_run["out"] / scene / cam / f"{index}.png")
        assert labels.shape == (h, w) and labels.dtype == np.uint8
        np.testing.assert_array_equal(labels, expected)
        # Where a surface is hit its depth is in range; where nothing is, 0.
        hit = labels != sndt.INVALID_LABEL
        assert hit.mean() > 0.5
        assert (depth[~hit] == 0).all()
        assert (depth[hit] > 0).all() and (depth[hit] < 20).all()


def test_rendered_depth_is_the_measured_depth_within_a_cell(python_map, trajectory):
    """Independent of the command line: the map renders the surfaces the frames measured,
    so the rendered planar depth agrees with the frame's depth to about a cell."""
    _, frames = trajectory
    f = frames[-1]
    h, w = f.shape
    labels, depth = python_map.render(f.pose, f.intrinsics, w, h)
    both = (labels != sndt.INVALID_LABEL) & np.isfinite(f.depth) & (f.depth > 0)
    err = np.abs(depth[both] - f.depth[both])
    assert np.median(err) < CELL / 2
    rng, _ = python_map.render(f.pose, f.intrinsics, w, h, depth_kind="range")
    np.testing.assert_array_equal(rng, labels)


def test_evaluate_gives_the_command_lines_metrics(python_map, trajectory, cli_run):
    traj, frames = trajectory
    m = sndt.evaluate(python_map, frames)
    expected = cli_run["metrics"]
    assert m.frames == len(frames)
    assert (m.miou, m.invr, m.mpacc) == (expected["miou"], expected["invr"], expected["mpacc"])
    assert m.per_class_iou == pytest.approx(expected["per_class_iou"], abs=0)
    # A trajectory is iterable too, and a list of (map, frames) pairs is the whole split.
    again = sndt.evaluate([(python_map, traj)])
    assert again.miou == m.miou


def test_load_reads_the_command_lines_snapshot(cli_run, tmp_path):
    m = sndt.Map.load(cli_run["snapshot"])
    assert m.capacity == sndt.DEFAULT_CAPACITY
    assert m.snapshot() == cli_run["snapshot"]
    path = tmp_path / "copy.sndt"
    m.save(path)
    assert path.read_bytes() == cli_run["snapshot"]
    assert sndt.Map.load(str(path)).checksum() == m.checksum()
    # A larger capacity holds the same voxels: same map, another header.
    big = sndt.Map.load(path, voxels=1 << 21)
    assert big.capacity == (1 << 21, 1 << 19)
    assert len(big) == len(m) and big.blocks == m.blocks
