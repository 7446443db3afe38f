"""Writes a ROS 2 bag (MCAP) from a prepared-layout trajectory with the independent
`mcap` / `mcap-ros2-support` Python packages and message definitions of their own: depth as
sensor_msgs/msg/Image 16UC1 (the layout's millimetres), labels as mono8, CameraInfo, and the
camera pose on /tf (world -> camera_link) with a fixed /tf_static (camera_link ->
camera_optical). sndt must map it to the same snapshot as the prepared layout.

    python bag_from_prepared.py ROOT SCENE/CAM OUT.mcap
"""
import json
import sys
from pathlib import Path

import png  # pypng
from mcap_ros2.writer import Writer

TIME = "int32 sec\nuint32 nanosec"
HEADER = "builtin_interfaces/Time stamp\nstring frame_id"
SEP = "\n" + "=" * 80 + "\n"


def definition(own, *deps):
    return own + "".join(f"{SEP}MSG: {name}\n{text}" for name, text in deps)


IMAGE = definition(
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
    "uint8 is_bigendian\nuint32 step\nuint8[] data",
    ("std_msgs/Header", HEADER), ("builtin_interfaces/Time", TIME))
CAMERA_INFO = definition(
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
    "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
    "uint32 binning_y\nRegionOfInterest roi",
    ("std_msgs/Header", HEADER), ("builtin_interfaces/Time", TIME),
    ("sensor_msgs/RegionOfInterest",
     "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify"))
TF = definition(
    "geometry_msgs/TransformStamped[] transforms",
    ("geometry_msgs/TransformStamped",
     "std_msgs/Header header\nstring child_frame_id\nTransform transform"),
    ("std_msgs/Header", HEADER), ("builtin_interfaces/Time", TIME),
    ("geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation"),
    ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z"),
    ("geometry_msgs/Quaternion", "float64 x\nfloat64 y\nfloat64 z\nfloat64 w"))


def stamp(ns):
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def transform(parent, child, ns, t, q):
    return {"header": {"stamp": stamp(ns), "frame_id": parent}, "child_frame_id": child,
            "transform": {"translation": dict(zip("xyz", t)), "rotation": dict(zip("xyzw", q))}}


IMAGE_TYPE = "sensor_msgs/msg/Image"
CAMERA_INFO_TYPE = "sensor_msgs/msg/CameraInfo"
TF_TYPE = "tf2_msgs/msg/TFMessage"
DEFINITIONS = {IMAGE_TYPE: IMAGE, CAMERA_INFO_TYPE: CAMERA_INFO, TF_TYPE: TF}
# Topic -> message type of the bag.
TOPICS = {"/tf_static": TF_TYPE, "/tf": TF_TYPE, "/camera/aligned_depth/image_raw": IMAGE_TYPE,
          "/segmentation/labels": IMAGE_TYPE, "/camera/aligned_depth/camera_info": CAMERA_INFO_TYPE}


def messages(root, trajectory):
    """The bag's messages in time order, per frame (frame index, topic, time in ns, message as
    nested dicts); /tf_static comes first with frame index 0."""
    root = Path(root)
    scene, cam = trajectory.split("/")
    ids = [l.strip() for l in (root / "test.txt").read_text().split() if l.startswith(trajectory + "/")]
    k = json.loads((root / "test" / "intrinsics" / scene / f"{cam}.json").read_text())
    # ROS puts pixel centres at integer coordinates, the layout at col + 0.5.
    fx, fy, cx, cy = k["fx"], k["fy"], k["cx"] - 0.5, k["cy"] - 0.5
    ns0 = 5_000_000_000
    fixed = transform("camera_link", "camera_optical", ns0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    yield 0, "/tf_static", ns0, {"transforms": [fixed]}
    for i, frame in enumerate(ids):
        ns = ns0 + 33_333_333 * i
        index = frame.split("/")[2]
        e = json.loads((root / "test" / "extrinsics" / scene / cam / f"{index}.json").read_text())
        # The layout's quaternion has OpenGL camera axes; the optical frame's is that
        # times a half turn about x: (w, x, y, z) = (-qx, qw, qz, -qy).
        q = (e["quat_w"], e["quat_z"], -e["quat_y"], -e["quat_x"])
        body = transform("world", "camera_link", ns, (e["x"], e["y"], e["z"]), q)
        yield i, "/tf", ns, {"transforms": [body]}
        header = {"stamp": stamp(ns), "frame_id": "camera_optical"}
        width, height, rows, _ = png.Reader(
            filename=str(root / "test" / "depth" / scene / cam / f"{index}.png")).read()
        depth = b"".join(int(v).to_bytes(2, "little") for row in rows for v in row)
        yield i, "/camera/aligned_depth/image_raw", ns, {
            "header": header, "height": height, "width": width, "encoding": "16UC1",
            "is_bigendian": 0, "step": 2 * width, "data": depth}
        _, _, rows, _ = png.Reader(
            filename=str(root / "test" / "semantic_40" / scene / cam / f"{index}.png")).read()
        labels = b"".join(bytes(row) for row in rows)
        yield i, "/segmentation/labels", ns, {
            "header": header, "height": height, "width": width, "encoding": "mono8",
            "is_bigendian": 0, "step": width, "data": labels}
        yield i, "/camera/aligned_depth/camera_info", ns, {
            "header": header, "height": height, "width": width,
            "distortion_model": "plumb_bob", "d": [0.0] * 5,
            "k": [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
            "r": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            "p": [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
            "binning_x": 0, "binning_y": 0,
            "roi": {"x_offset": 0, "y_offset": 0, "height": 0, "width": 0, "do_rectify": False},
        }


def main(root, trajectory, out):
    frames = set()
    with open(out, "wb") as f:
        w = Writer(f)
        schemas = {name: w.register_msgdef(name, text) for name, text in DEFINITIONS.items()}
        for i, topic, ns, msg in messages(root, trajectory):
            w.write_message(topic, schemas[TOPICS[topic]], msg, log_time=ns, publish_time=ns)
            frames.add(i)
        w.finish()
    print(f"wrote {out}: {len(frames)} frames of {trajectory}")


if __name__ == "__main__":
    main(*sys.argv[1:])
