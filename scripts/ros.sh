#!/usr/bin/env bash
# ROS 2 bags against an independent implementation: the Python packages mcap and
# mcap-ros2-support (installed into target/ros-venv, idempotently) (a) write a bag from a
# synthetic prepared-layout trajectory with message definitions of their own, which
# `sndt map` must map to the same snapshot as the prepared layout; (b) read back the map bag
# of `sndt export --mcap` and check its fields, counts and values against the PLY of the
# same map.
set -euo pipefail
cd "$(dirname "$0")/.."

VENV=target/ros-venv
WORK=target/ros-check
step() { printf '\n==> %s\n' "$*"; }

step "Python reader/writer (mcap, mcap-ros2-support, pypng) in $VENV"
if ! "$VENV/bin/python" -c 'import mcap, mcap_ros2, png' 2>/dev/null; then
    if ! python3 -m venv "$VENV" 2>/dev/null; then
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -qq
        apt-get install -y -qq --no-install-recommends python3-venv
        python3 -m venv "$VENV"
    fi
    "$VENV/bin/pip" install -q 'mcap==1.*' 'mcap-ros2-support==0.5.*' 'pypng==0.20220715.*'
fi

step "a synthetic trajectory: prepared layout (sndt synth) and a bag written by Python"
# The dev profile (opt-level 2, see Cargo.toml) shares its build with the rest of the
# test command; a release build would cost a minute more.
cargo build -q -p sndt-host --bin sndt
SNDT=target/debug/sndt
rm -rf "$WORK" && mkdir -p "$WORK"
"$SNDT" synth --scenes 1 --frames-per-scene 8 --no-predictions --out "$WORK/prepared" >/dev/null
"$VENV/bin/python" scripts/ros/bag_from_prepared.py "$WORK/prepared" synth_00_living/cam_00 "$WORK/python.mcap"
"$SNDT" info "$WORK/python.mcap"

step "sndt map: the bag and the prepared layout give the same snapshot"
"$SNDT" map "$WORK/python.mcap" --cell 0.1 --save-maps --out "$WORK/from-bag" >/dev/null
"$SNDT" map "$WORK/prepared" --cell 0.1 --save-maps --out "$WORK/from-layout" >/dev/null
bag_map=$(find "$WORK/from-bag/maps" -name '*.sndt')
layout_map=$(find "$WORK/from-layout/maps" -name '*.sndt')
crc() { python3 -c 'import sys, zlib; print("%08x" % zlib.crc32(open(sys.argv[1], "rb").read()))' "$1"; }
printf 'snapshot file CRC-32: bag %s, prepared layout %s\n' "$(crc "$bag_map")" "$(crc "$layout_map")"
if ! cmp -s "$bag_map" "$layout_map"; then
    echo "error: the bag written by Python maps to another snapshot than the prepared layout" >&2
    exit 1
fi

step "sndt export --mcap, read back by Python"
"$SNDT" export "$WORK/python.mcap" --mcap "$WORK/map.mcap" --ply "$WORK/map.ply" --mcap-interval 3
"$VENV/bin/python" scripts/ros/check_map_bag.py "$WORK/map.mcap" "$WORK/map.ply" 3
echo "ros bags: ok"
