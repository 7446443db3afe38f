"""Shared fixtures: the `sndt` command line's own run on the frames the tests map from
Python, so that every comparison is against the other implementation of the same job."""

import json
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import sndt

# Eight frames of one synthetic room at 10 cm: big enough to fill a map with every kind
# of voxel, small enough to map in seconds.
SPEC = "synthetic:1:8"
CELL = 0.1


def sndt_binary() -> str:
    """The command line: $SNDT_BIN (scripts/python.sh sets it), else `sndt` on PATH."""
    path = os.environ.get("SNDT_BIN") or shutil.which("sndt")
    if not path:
        pytest.fail("set SNDT_BIN to the sndt binary (cargo build -p sndt-host --bin sndt)")
    return path


@pytest.fixture(scope="session")
def cli_run(tmp_path_factory):
    """`sndt map SPEC --cell 0.1 --save-maps`: its snapshot, PNGs and metrics."""
    out = tmp_path_factory.mktemp("cli") / "map"
    subprocess.run(
        [sndt_binary(), "map", SPEC, "--cell", str(CELL), "--save-maps", "--out", str(out)],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    maps = sorted((out / "maps").glob("*.sndt"))
    assert len(maps) == 1, maps
    return {
        "out": out,
        "snapshot": maps[0].read_bytes(),
        "metrics": json.loads((out / "metrics.json").read_text()),
    }


@pytest.fixture(scope="session")
def trajectory():
    """The one trajectory of SPEC, its frames read once."""
    (traj,) = sndt.open_dataset(SPEC).trajectories
    return traj, list(traj)


@pytest.fixture(scope="session")
def python_map(trajectory):
    """SPEC mapped from Python, frame by frame from numpy arrays."""
    _, frames = trajectory
    m = sndt.Map(cell=CELL)
    for f in frames:
        m.integrate(f.depth, f.labels, intrinsics=f.intrinsics, pose=f.pose, depth_kind=f.depth_kind)
    return m


def wall_frame(h=48, w=64, z=2.0, label=1):
    """A camera at the origin looking at a flat wall `z` metres ahead, all of class `label`."""
    depth = np.full((h, w), z, dtype=np.float32)
    labels = np.full((h, w), label, dtype=np.uint8)
    intrinsics = (50.0, 50.0, w / 2, h / 2)
    return depth, labels, intrinsics, np.eye(4)


def repo_root() -> pathlib.Path:
    return pathlib.Path(__file__).resolve().parents[2]
