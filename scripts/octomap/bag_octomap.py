"""Reads the OctoMap message of a map bag written by `sndt export --mcap` with the
independent `mcap` / `mcap-ros2-support` Python readers (decoding it by the message
definition the bag carries) and writes its tree data to a file for liboctomap
(check_octomap.cpp, mode msg). Checks the message's fields and that its data is the tree of
the `.bt` file that the same export wrote, byte for byte.

    python bag_octomap.py MAP.mcap MAP.bt RESOLUTION OUT.data
"""
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

TOPIC = "/octomap_binary"


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def main(bag, bt, resolution, out):
    found = []
    with open(bag, "rb") as f:
        for schema, channel, _, msg in make_reader(
                f, decoder_factories=[DecoderFactory()]).iter_decoded_messages(topics=[TOPIC]):
            if schema.name != "octomap_msgs/msg/Octomap" or schema.encoding != "ros2msg":
                fail(f"{channel.topic}: schema {schema.name} ({schema.encoding})")
            found.append(msg)
    if not found:
        fail(f"{bag}: no message on {TOPIC}")
    msg = found[-1]
    if not (msg.binary and msg.id == "OcTree" and msg.resolution == float(resolution)):
        fail(f"binary {msg.binary}, id {msg.id!r}, resolution {msg.resolution}")
    if msg.header.frame_id != "sndt_map":
        fail(f"frame {msg.header.frame_id!r}")
    # int8[]: a list of signed numbers (or bytes, by reader version).
    data = msg.data if isinstance(msg.data, bytes) else bytes(b & 0xFF for b in msg.data)
    tree = open(bt, "rb").read().split(b"\ndata\n", 1)[1]
    if data != tree:
        fail(f"{len(data)} bytes of data, the .bt's tree has {len(tree)} or other bytes")
    open(out, "wb").write(data)
    print(f"{bag}: {len(found)} {TOPIC} message(s), the last: OcTree, binary, res {msg.resolution}, "
          f"{len(data)} bytes = the .bt's tree")


if __name__ == "__main__":
    main(*sys.argv[1:])
