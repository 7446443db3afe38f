"""What the ROS 2 check scripts beside this file share: how a check fails, and the point
layout of the PointCloud2 messages in sndt's map bags."""
import sys

# The fields of a map bag's PointCloud2, as (name, byte offset, datatype): sensor_msgs'
# PointField datatypes 7 (FLOAT32) and 2 (UINT8); 28 bytes a point.
MAP_CLOUD_FIELDS = [("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("rgb", 12, 7), ("confidence", 16, 7),
                    ("occupancy", 20, 7), ("class", 24, 2)]


def fail(msg):
    """Prints why the check failed and exits with status 1, which stops the calling script."""
    print("FAIL:", msg)
    sys.exit(1)
