"""Writes a bag folder as `ros2 bag record --max-bag-duration` leaves it, split into three
files: OUT/metadata.yaml and OUT/<name>_0.mcap, _1.mcap, _2.mcap (name: OUT's name), from
the same prepared-layout trajectory and with the same messages as bag_from_prepared.py. Each
file is written by the independent `rosbags` library (rosbag2 writer, MCAP storage, message
types from its ROS 2 Humble type store) as a bag of its own; the folder's metadata.yaml
joins theirs. /tf_static is in the first file only, as a recorder that started before the
latched publisher would have it. The folder is then read back with rosbags' reader.

    python folder_from_prepared.py ROOT SCENE/CAM OUT
"""
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np
from rosbags.interfaces import (Qos, QosDurability, QosHistory, QosLiveliness, QosReliability,
                                QosTime)
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
from ruamel.yaml import YAML

from bag_from_prepared import CAMERA_INFO_TYPE, IMAGE_TYPE, TF_TYPE, TOPICS, messages
from common import fail

PARTS = 3
STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types


def header(d):
    stamp = T["builtin_interfaces/msg/Time"](**d["stamp"])
    return T["std_msgs/msg/Header"](stamp=stamp, frame_id=d["frame_id"])


def image(d):
    return T[IMAGE_TYPE](
        header=header(d["header"]), height=d["height"], width=d["width"], encoding=d["encoding"],
        is_bigendian=d["is_bigendian"], step=d["step"], data=np.frombuffer(d["data"], np.uint8))


def camera_info(d):
    return T[CAMERA_INFO_TYPE](
        header=header(d["header"]), height=d["height"], width=d["width"],
        distortion_model=d["distortion_model"], d=np.array(d["d"], np.float64),
        k=np.array(d["k"], np.float64), r=np.array(d["r"], np.float64),
        p=np.array(d["p"], np.float64), binning_x=d["binning_x"], binning_y=d["binning_y"],
        roi=T["sensor_msgs/msg/RegionOfInterest"](**d["roi"]))


def tf(d):
    def one(t):
        tr = t["transform"]
        return T["geometry_msgs/msg/TransformStamped"](
            header=header(t["header"]), child_frame_id=t["child_frame_id"],
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](**tr["translation"]),
                rotation=T["geometry_msgs/msg/Quaternion"](**tr["rotation"])))
    return T[TF_TYPE](transforms=[one(t) for t in d["transforms"]])


BUILD = {IMAGE_TYPE: image, CAMERA_INFO_TYPE: camera_info, TF_TYPE: tf}


def qos(topic):
    """What the publishers offer: latched /tf_static, the rest volatile."""
    infinite = QosTime(9223372036, 854775807)
    latched = topic == "/tf_static"
    return Qos(QosHistory.KEEP_LAST, 1 if latched else 10, QosReliability.RELIABLE,
               QosDurability.TRANSIENT_LOCAL if latched else QosDurability.VOLATILE,
               infinite, infinite, QosLiveliness.AUTOMATIC, infinite, False)


def write_part(path, msgs):
    """One file's bag: every topic declared (as each file of a split recording does), `msgs`."""
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns = {topic: w.add_connection(topic, kind, typestore=STORE, offered_qos_profiles=[qos(topic)])
                 for topic, kind in TOPICS.items()}
        for topic, ns, msg in msgs:
            kind = TOPICS[topic]
            w.write(conns[topic], ns, STORE.serialize_cdr(BUILD[kind](msg), kind))
    [mcap] = path.glob("*.mcap")
    return mcap, YAML(typ="safe").load((path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]


def join(parts):
    """The folder's metadata from its files' (in order): counts summed, files listed."""
    first = dict(parts[0])
    start = min(p["starting_time"]["nanoseconds_since_epoch"] for p in parts)
    end = max(p["starting_time"]["nanoseconds_since_epoch"] + p["duration"]["nanoseconds"] for p in parts)
    counts = {}
    for p in parts:
        for t in p["topics_with_message_count"]:
            counts[t["topic_metadata"]["name"]] = counts.get(t["topic_metadata"]["name"], 0) + t["message_count"]
    for t in first["topics_with_message_count"]:
        t["message_count"] = counts[t["topic_metadata"]["name"]]
    first["starting_time"] = {"nanoseconds_since_epoch": start}
    first["duration"] = {"nanoseconds": end - start}
    first["message_count"] = sum(p["message_count"] for p in parts)
    first["files"] = [f for p in parts for f in p["files"]]
    first["relative_file_paths"] = [f["path"] for f in first["files"]]
    return {"rosbag2_bagfile_information": first}


def main(root, trajectory, out):
    out = Path(out)
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    everything = list(messages(root, trajectory))
    frames = max(i for i, _, _, _ in everything) + 1
    split = [[] for _ in range(PARTS)]
    for i, topic, ns, msg in everything:
        split[i * PARTS // frames].append((topic, ns, msg))
    parts = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, msgs in enumerate(split):
            # rosbags names a bag's file after its folder: <name>_<k>/<name>_<k>.mcap.
            mcap, meta = write_part(Path(tmp) / f"{out.name}_{k}", msgs)
            shutil.move(mcap, out / mcap.name)
            parts.append(meta)
    yaml = YAML(typ="safe")
    yaml.default_flow_style = False
    with open(out / "metadata.yaml", "w") as f:
        yaml.dump(join(parts), f)
    total = sum(len(m) for m in split)
    with Reader(out) as reader:
        files = [x.path.name for x in reader.storage.storages]
        n, declared = sum(1 for _ in reader.messages()), reader.message_count
    if files != [f"{out.name}_{k}.mcap" for k in range(PARTS)] or n != total or declared != total:
        fail(f"{out}: rosbags reads {files}, {n} messages (metadata.yaml {declared}), wrote {total}")
    print(f"wrote {out}: {frames} frames of {trajectory}, {total} messages in {', '.join(files)}")


if __name__ == "__main__":
    main(*sys.argv[1:])
