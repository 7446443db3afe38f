"""The classes and dicts that copy a core or host struct field by field have exactly that
struct's fields: ``FrameReport`` (the core's ``FrameReport``), ``CONFIG_FIELDS`` and
``Map.config`` (``Config``), ``Map.stats`` (``MapStats``) and ``Metrics`` (the host's
``Metrics``). The structs' fields are read from their Rust source, so a field added there
fails here until the package and its stub show it. (The conversions in python/src take
each struct apart without ``..``, so most such changes already fail to compile; these
tests also catch a name, a stub or a keyword left behind.)"""

import re

import numpy as np

import sndt
from conftest import repo_root, wall_frame


def struct_fields(crate: str, name: str):
    """The field names of ``pub struct name { ... }`` in the one file of ``crate/src`` that
    defines it, in order."""
    found = []
    for path in sorted((repo_root() / crate / "src").rglob("*.rs")):
        text = path.read_text()
        match = re.search(r"^pub struct " + name + r" \{\n(.*?)^\}", text, re.S | re.M)
        if match:
            found.append(re.findall(r"^    pub (\w+):", match.group(1), re.M))
    assert len(found) == 1, f"{crate}: {len(found)} definitions of {name}"
    return found[0]


def stub_attributes(name: str):
    """The attribute names the stub declares in ``class name:``, in order."""
    stub = (repo_root() / "python" / "sndt" / "_sndt.pyi").read_text()
    match = re.search(r"^class " + name + r":\n(.*?)(?=^\S)", stub, re.S | re.M)
    assert match, f"no class {name} in the stub"
    return re.findall(r"^    (\w+): ", match.group(1), re.M)


def public_attributes(cls):
    return {a for a in vars(cls) if not a.startswith("_")}


def test_the_scanners_read_a_known_struct_and_stub_class():
    assert struct_fields("core", "MapStats")[0] == "frames"
    assert stub_attributes("Voxels")[:2] == ["means", "covariances"]


def test_frame_report_has_every_field_of_the_core_s():
    core = struct_fields("core", "FrameReport")
    assert len(core) >= 15
    assert public_attributes(sndt.FrameReport) == set(core)
    assert stub_attributes("FrameReport") == core


def test_frame_report_values_come_from_their_own_fields():
    """Counts known by construction, and counts checked against ``Map.stats`` (which the
    core keeps apart from the report): a value copied from the wrong core field shows."""
    pixels = 48 * 64
    depth, labels, k, pose = wall_frame(h=48, w=64, z=2.0)
    depth[:8] = np.nan  # 512 pixels without a measurement
    depth[8:12] = 100.0  # 256 points beyond max_range (20 m)
    r = sndt.Map(cell=0.1).integrate(depth, labels, intrinsics=k, pose=pose)
    assert (r.rejected_depth, r.truncated, r.points_used) == (512, 256, pixels - 768)
    assert r.rejected_label == r.rejected_out_of_range == 0
    # A new map: every end voxel is a new voxel; the truncated points cast rays too.
    assert 0 < r.end_voxels == r.voxels_created < r.rays and r.blocks_created > 0
    assert r.records_spilled == r.records_dropped == 0  # a Map has no spill sink

    # A map too small for one wall at 2 cm drops points and free-space updates.
    full = sndt.Map(cell=0.02, voxels=1024, blocks=128)
    depth, labels, k, pose = wall_frame()
    r = full.integrate(depth, labels, intrinsics=k, pose=pose)
    assert r.points_used + r.dropped_points == pixels and r.dropped_points > 0
    assert (r.dropped_points, r.dropped_misses) == (full.stats["dropped_points"], full.stats["dropped_misses"])
    assert r.dropped_misses not in (0, r.dropped_points)

    # A map with room for one wall at 7 cm evicts it for a second wall 10 m away.
    small = sndt.Map(cell=0.07, voxels=4096, blocks=512)
    small.integrate(depth, labels, intrinsics=k, pose=pose)
    aside = np.eye(4)
    aside[0, 3] = 10.0
    r = small.integrate(depth, labels, intrinsics=k, pose=aside)
    assert (r.voxels_evicted, r.blocks_evicted) == (small.stats["voxels_evicted"], small.stats["blocks_evicted"])
    assert r.voxels_evicted not in (0, r.blocks_evicted) and r.blocks_evicted > 0
    assert r.dropped_points == r.dropped_misses == 0


def test_config_fields_are_the_core_s():
    core = struct_fields("core", "Config")
    keywords = ["cell_size" if f == "cell" else "lambda" if f == "lambda_" else f for f in sndt.CONFIG_FIELDS]
    assert keywords == core
    config = sndt.Map(cell=0.1, voxels=1024, blocks=128).config
    assert [("lambda" if f == "lambda_" else f) for f in config] == core
    # Every field is a keyword the constructor takes (its default given back unchanged).
    for field in sndt.CONFIG_FIELDS[1:]:
        again = sndt.Map(cell=0.1, voxels=1024, blocks=128, **{field: config[field]})
        assert again.config == config, field


def test_map_stats_are_the_core_s():
    assert list(sndt.Map(voxels=1024, blocks=128).stats) == struct_fields("core", "MapStats")


def test_metrics_are_the_host_s_and_the_frame_count():
    host = struct_fields("host", "Metrics")
    # The host's per-class array `iou` is `per_class_iou`, by class name.
    expected = ["per_class_iou" if f == "iou" else f for f in host] + ["frames"]
    assert public_attributes(sndt.Metrics) == set(expected)
    assert sorted(stub_attributes("Metrics")) == sorted(expected)
