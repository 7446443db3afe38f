"""Reads a map bag written by `sndt export --mcap` with the independent `mcap` /
`mcap-ros2-support` Python readers and checks it against the PLY that the same command
wrote from the same map: the last PointCloud2 has the documented fields, one point per PLY
vertex, the same coordinates and colours; classes, confidences and occupancies are in range;
the MarkerArray holds a delete-all and one ellipsoid per point; /tf_static places sndt_map.

    python check_map_bag.py MAP.mcap MAP.ply SNAPSHOTS
"""
import struct
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from common import MAP_CLOUD_FIELDS, fail


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    n = int(header.split("element vertex ")[1].split()[0])
    return [struct.unpack_from("<3f3B", data, end + 15 * i) for i in range(n)]


def main(bag, ply, snapshots):
    clouds, markers, statics = [], [], []
    with open(bag, "rb") as f:
        for schema, channel, message, msg in make_reader(
                f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            if channel.message_encoding != "cdr" or schema.encoding != "ros2msg":
                fail(f"{channel.topic}: encoding {channel.message_encoding}/{schema.encoding}")
            if schema.name == "sensor_msgs/msg/PointCloud2":
                clouds.append(msg)
            elif schema.name == "visualization_msgs/msg/MarkerArray":
                markers.append(msg)
            elif channel.topic == "/tf_static":
                statics += [(t.header.frame_id, t.child_frame_id) for t in msg.transforms]
    if len(clouds) != int(snapshots) or len(markers) != int(snapshots):
        fail(f"{len(clouds)} clouds and {len(markers)} marker arrays, expected {snapshots}")
    if ("world", "sndt_map") not in statics:
        fail(f"/tf_static has {statics}")
    cloud, vertices = clouds[-1], read_ply(ply)
    if [(x.name, x.offset, x.datatype) for x in cloud.fields] != MAP_CLOUD_FIELDS:
        fail(f"fields {[(x.name, x.offset, x.datatype) for x in cloud.fields]}")
    if cloud.width != len(vertices) or cloud.point_step != 28 or len(cloud.data) != 28 * cloud.width:
        fail(f"{cloud.width} points, {len(vertices)} PLY vertices")
    for i, (px, py, pz, r, g, b) in enumerate(vertices):
        x, y, z, rgb, conf, occ = struct.unpack_from("<6f", cloud.data, 28 * i)
        cls = cloud.data[28 * i + 24]
        packed = struct.unpack("<I", struct.pack("<f", rgb))[0]
        if (x, y, z) != (px, py, pz) or packed != (r << 16 | g << 8 | b):
            fail(f"point {i}: {(x, y, z, hex(packed))} vs PLY {(px, py, pz, r, g, b)}")
        if not (0 <= cls <= 40 and 0.0 <= conf <= 1.0 and 0.5 < occ < 1.0):
            fail(f"point {i}: class {cls}, confidence {conf}, occupancy {occ}")
    last = markers[-1].markers
    if last[0].action != 3 or len(last) != cloud.width + 1 or any(m.type != 2 for m in last[1:]):
        fail(f"{len(last)} markers for {cloud.width} points")
    print(f"{bag}: {len(clouds)} snapshots, {cloud.width} points = PLY vertices, fields and values ok")


if __name__ == "__main__":
    main(*sys.argv[1:])
