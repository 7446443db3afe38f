"""Opens bags written by sndt, unmodified, with the independent `rosbags` library (its rosbag2
reader, which takes a bare .mcap file as well as a bag folder, and its ROS 2 Humble type
store), deserializes every message of every topic and checks what sndt wrote:

- the MCAP header (read with the `mcap` package): profile `ros2`, a library naming sndt,
  and a `rosbag2` metadata record with ROS_DISTRO humble;
- per topic the QoS rosbag2 recorded: reliable, keep last, /tf_static transient local (so
  that playback latches it), every other topic volatile; message counts as declared;
- a folder: metadata.yaml version 5, storage mcap, its counts and time span as read;
- `frames N` (sndt synth): N depth images (16UC1), labels (mono8), camera infos and /tf
  transforms of one size and frame, and one /tf_static;
- `map N` (sndt map / sndt export): N point clouds of the documented fields, N marker
  arrays (a delete-all, then one ellipsoid per point) and N binary OcTrees
  (octomap_msgs, whose type the bag's own definition gives), /tf_static placing sndt_map;
- bags named together (a file and a folder from the same command) hold the same messages.

    python check_rosbags.py frames|map N BAG [BAG...]
"""
import sys
from pathlib import Path

from mcap.reader import make_reader
from rosbags.interfaces import QosDurability, QosHistory, QosReliability
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from ruamel.yaml import YAML

from common import MAP_CLOUD_FIELDS, fail

STORE = get_typestore(Stores.ROS2_HUMBLE)
IMAGE = "sensor_msgs/msg/Image"
CLOUD = "sensor_msgs/msg/PointCloud2"
MARKERS = "visualization_msgs/msg/MarkerArray"
OCTOMAP = "octomap_msgs/msg/Octomap"


def check_mcap_header(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        records = [(m.name, m.metadata) for m in reader.iter_metadata()]
    if header.profile != "ros2" or not header.library.startswith("sndt "):
        fail(f"{path}: profile {header.profile!r}, library {header.library!r}")
    if records != [("rosbag2", {"ROS_DISTRO": "humble"})]:
        fail(f"{path}: metadata records {records}")


def check_qos(bag, conn):
    [qos] = conn.ext.offered_qos_profiles
    durability = QosDurability.TRANSIENT_LOCAL if conn.topic == "/tf_static" else QosDurability.VOLATILE
    if (qos.durability, qos.reliability, qos.history) != (
            durability, QosReliability.RELIABLE, QosHistory.KEEP_LAST):
        fail(f"{bag} {conn.topic}: QoS {qos}")
    if conn.ext.serialization_format != "cdr":
        fail(f"{bag} {conn.topic}: serialization {conn.ext.serialization_format}")


def register(conn):
    """A type the Humble store lacks (octomap_msgs is not part of ROS 2's core) is taken
    from the definition the bag carries: its own text, before the dependencies that
    rosbag2 appends (those are in the store)."""
    if conn.msgtype in STORE.fielddefs:
        return
    own = conn.msgdef.data.split("=" * 80)[0]
    STORE.register(get_types_from_msg(own, conn.msgtype))


def read(bag):
    """Every message of `bag` as (topic, time, raw, decoded), and per topic its type."""
    out, types = [], {}
    with Reader(bag) as reader:
        for conn in reader.connections:
            check_qos(bag, conn)
            register(conn)
            types[conn.topic] = conn.msgtype
        counts = dict.fromkeys(types, 0)
        for conn, t, raw in reader.messages():
            out.append((conn.topic, t, bytes(raw), STORE.deserialize_cdr(raw, conn.msgtype)))
            counts[conn.topic] += 1
        declared = {c.topic: c.msgcount for c in reader.connections}
        if counts != declared or len(out) != reader.message_count:
            fail(f"{bag}: read {counts}, declared {declared}, total {reader.message_count}")
        times = [t for _, t, _, _ in out]
        if (reader.start_time, reader.end_time) != (min(times), max(times) + 1):
            fail(f"{bag}: span {reader.start_time}..{reader.end_time}, messages {min(times)}..{max(times)}")
        if bag.is_dir():
            check_folder(bag, reader, out)
    return out, types


def check_folder(bag, reader, msgs):
    meta = reader.storage
    files = [s.path for s in meta.storages]
    if files != [bag / f"{bag.name}_0.mcap"]:
        fail(f"{bag}: files {files}")
    info = meta.files[0]
    times = [t for _, t, _, _ in msgs]
    if (info["message_count"], info["starting_time"]["nanoseconds_since_epoch"],
            info["duration"]["nanoseconds"]) != (len(msgs), min(times), max(times) - min(times)):
        fail(f"{bag}: metadata.yaml files entry {info}")
    top = YAML(typ="safe").load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    if (top["version"], top["storage_identifier"], top["compression_mode"]) != (5, "mcap", ""):
        fail(f"{bag}: metadata.yaml version {top['version']}, storage {top['storage_identifier']}")


def check_frames(bag, msgs, n):
    by_topic = {}
    for topic, _, _, m in msgs:
        by_topic.setdefault(topic, []).append(m)
    counts = {t: len(v) for t, v in by_topic.items()}
    expected = {"/tf_static": 1, "/tf": n, "/camera/depth/image_rect_raw": n,
                "/camera/semantic/labels": n, "/camera/depth/camera_info": n}
    if counts != expected:
        fail(f"{bag}: {counts}, expected {expected}")
    info = by_topic["/camera/depth/camera_info"][0]
    for topic, encoding, bpp in [("/camera/depth/image_rect_raw", "16UC1", 2),
                                 ("/camera/semantic/labels", "mono8", 1)]:
        for im in by_topic[topic]:
            if (im.encoding, im.width, im.height, im.step, len(im.data), im.header.frame_id) != (
                    encoding, info.width, info.height, bpp * info.width,
                    bpp * info.width * info.height, "camera_depth_optical_frame"):
                fail(f"{bag} {topic}: {im.encoding} {im.width}x{im.height} step {im.step} "
                     f"{len(im.data)} bytes in {im.header.frame_id}")
    if max(max(im.data) for im in by_topic["/camera/semantic/labels"]) > 40:
        fail(f"{bag}: a label above NYU40's 40")
    tf = {(t.header.frame_id, t.child_frame_id) for m in by_topic["/tf"] for t in m.transforms}
    static = [(t.header.frame_id, t.child_frame_id) for t in by_topic["/tf_static"][0].transforms]
    if tf != {("world", "base_link")} or static != [("base_link", "camera_depth_optical_frame")]:
        fail(f"{bag}: /tf {tf}, /tf_static {static}")
    return f"{n} frames of {info.width}x{info.height}"


def check_map(bag, msgs, n):
    clouds = [m for _, _, _, m in msgs if m.__msgtype__ == CLOUD]
    markers = [m for _, _, _, m in msgs if m.__msgtype__ == MARKERS]
    if len(clouds) != n or len(markers) != n:
        fail(f"{bag}: {len(clouds)} clouds and {len(markers)} marker arrays, expected {n}")
    for cloud, array in zip(clouds, markers):
        fields = [(f.name, f.offset, f.datatype) for f in cloud.fields]
        if fields != MAP_CLOUD_FIELDS or cloud.point_step != 28 or len(cloud.data) != 28 * cloud.width:
            fail(f"{bag}: cloud of {cloud.width} points, fields {fields}, {len(cloud.data)} bytes")
        if cloud.header.frame_id != "sndt_map" or cloud.height != 1:
            fail(f"{bag}: cloud in {cloud.header.frame_id}, height {cloud.height}")
        ms = array.markers
        if ms[0].action != 3 or len(ms) != cloud.width + 1 or any(m.type != 2 for m in ms[1:]):
            fail(f"{bag}: {len(ms)} markers for {cloud.width} points")
    octomaps = [m for _, _, _, m in msgs if m.__msgtype__ == OCTOMAP]
    if len(octomaps) != n:
        fail(f"{bag}: {len(octomaps)} octomaps, expected {n}")
    for o in octomaps:
        if (o.header.frame_id, o.binary, o.id, len(o.data) > 0) != ("sndt_map", True, "OcTree", True):
            fail(f"{bag}: octomap {o.id} binary {o.binary} in {o.header.frame_id}, {len(o.data)} bytes")
    static = [(t.header.frame_id, t.child_frame_id)
              for topic, _, _, m in msgs if topic == "/tf_static" for t in m.transforms]
    if static != [("world", "sndt_map")]:
        fail(f"{bag}: /tf_static {static}")
    return f"{n} snapshots, last {clouds[-1].width} points"


def main(kind, n, *bags):
    check = {"frames": check_frames, "map": check_map}[kind]
    first = None
    for bag in map(Path, bags):
        for f in sorted(bag.glob("*.mcap")) if bag.is_dir() else [bag]:
            check_mcap_header(f)
        msgs, types = read(bag)
        what = check(bag, msgs, int(n))
        raw = [(topic, t, data) for topic, t, data, _ in msgs]
        if first is None:
            first = (bag, raw)
        elif raw != first[1]:
            fail(f"{bag} holds other messages than {first[0]}")
        form = "folder" if bag.is_dir() else "file"
        print(f"rosbags reads {bag} ({form}): {len(msgs)} messages on {len(types)} topics, {what}")


if __name__ == "__main__":
    main(*sys.argv[1:])
