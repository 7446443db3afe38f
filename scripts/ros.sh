#!/usr/bin/env bash
# ROS 2 bags against independent implementations, installed into target/ros-venv
# (idempotently): the Python packages mcap and mcap-ros2-support, and the rosbags library
# (rosbag2 reader and writer, ROS 2 Humble type store).
#  (a) a bag written by mcap-ros2-support from a synthetic prepared-layout trajectory, with
#      message definitions of its own, maps to the same snapshot as the prepared layout;
#  (b) the map bag of `sndt export --mcap` read back by mcap-ros2-support matches the PLY
#      of the same map;
#  (c) rosbags opens every bag sndt writes (`sndt synth`, `sndt map`, `sndt export` with
#      --mcap, each as one .mcap file and as a bag folder), unmodified, and checks its
#      header, QoS, counts and fields;
#  (d) a bag folder split into three files, written by rosbags from the same trajectory,
#      maps to the same snapshot as the prepared layout.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

VENV=target/ros-venv
WORK=target/ros-check

step "Python readers/writers (mcap, mcap-ros2-support, rosbags, pypng) in $VENV"
ensure_ros_venv "$VENV"
PY="$VENV/bin/python"

step "a synthetic trajectory: prepared layout and bags (sndt synth), a bag written by Python"
# The dev profile (opt-level 2, see Cargo.toml) and `--workspace` (features resolved as
# `cargo test --workspace` resolves them) share the build with the rest of the test
# command; a release build would cost a minute more.
cargo build -q --workspace --bin sndt
SNDT=${CARGO_TARGET_DIR:-target}/debug/sndt
rm -rf "$WORK" && mkdir -p "$WORK"
"$SNDT" synth --scenes 1 --frames-per-scene 8 --no-predictions --out "$WORK/prepared" \
    --mcap "$WORK/synth.mcap" >/dev/null
"$SNDT" synth --scenes 1 --frames-per-scene 8 --no-predictions --mcap "$WORK/synth/" >/dev/null
"$PY" scripts/ros/bag_from_prepared.py "$WORK/prepared" synth_00_living/cam_00 "$WORK/python.mcap"
"$SNDT" info "$WORK/python.mcap"

step "sndt map: the bag and the prepared layout give the same snapshot"
"$SNDT" map "$WORK/python.mcap" --cell 0.1 --save-maps --out "$WORK/from-bag" >/dev/null
"$SNDT" map "$WORK/prepared" --cell 0.1 --save-maps --out "$WORK/from-layout" \
    --mcap "$WORK/map.mcap" --mcap-interval 4 >/dev/null
"$SNDT" map "$WORK/prepared" --cell 0.1 --out "$WORK/from-layout-2" \
    --mcap "$WORK/map/" --mcap-interval 4 >/dev/null
layout_map=$(find "$WORK/from-layout/maps" -name '*.sndt')
crc() { python3 -c 'import sys, zlib; print("%08x" % zlib.crc32(open(sys.argv[1], "rb").read()))' "$1"; }
same_snapshot() { # what, directory of the map run
    local map
    map=$(find "$2/maps" -name '*.sndt')
    printf 'snapshot file CRC-32: %s %s, prepared layout %s\n' "$1" "$(crc "$map")" "$(crc "$layout_map")"
    if ! cmp -s "$map" "$layout_map"; then
        echo "error: the $1 maps to another snapshot than the prepared layout" >&2
        exit 1
    fi
}
same_snapshot "bag written by Python" "$WORK/from-bag"

step "sndt export --mcap, read back by Python"
"$SNDT" export "$WORK/python.mcap" --mcap "$WORK/export.mcap" --ply "$WORK/map.ply" --mcap-interval 3
"$SNDT" export "$WORK/python.mcap" --mcap "$WORK/export/" --mcap-interval 3 >/dev/null
"$PY" scripts/ros/check_map_bag.py "$WORK/export.mcap" "$WORK/map.ply" 3

step "rosbags (Humble type store) reads every bag sndt wrote, as files and as folders"
"$PY" scripts/ros/check_rosbags.py frames 8 "$WORK/synth.mcap" "$WORK/synth"
"$PY" scripts/ros/check_rosbags.py map 2 "$WORK/map.mcap" "$WORK/map"
"$PY" scripts/ros/check_rosbags.py map 3 "$WORK/export.mcap" "$WORK/export"

step "a bag folder split into three files by rosbags: sndt map gives the same snapshot"
"$PY" scripts/ros/folder_from_prepared.py "$WORK/prepared" synth_00_living/cam_00 "$WORK/split"
"$SNDT" map "$WORK/split" --cell 0.1 --save-maps --out "$WORK/from-split" >/dev/null
same_snapshot "split bag folder written by rosbags" "$WORK/from-split"
echo "ros bags: ok"
