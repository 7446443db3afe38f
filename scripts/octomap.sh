#!/usr/bin/env bash
# OctoMap export against liboctomap itself: maps a small synthetic trajectory, exports its
# occupancy layer as a binary OcTree (.bt), a ColorOcTree (.ot) and an
# octomap_msgs/Octomap message in a map bag, reads each back with Debian's liboctomap-dev
# (scripts/octomap/check_octomap.cpp lists every leaf, and has liboctomap encode the leaves
# it read into a tree of its own, which must be the file's bytes) and queries sndt's own map
# at every leaf's centre (host/examples/octomap_check.rs): every leaf must agree with sndt's
# occupancy there (and for the .ot with its log-odds and class colour), and the leaves must
# be as many as sndt's known voxels. The bag's message is decoded by the Python mcap
# packages (in target/ros-venv, as scripts/ros.sh installs them) and must carry the .bt's
# tree byte for byte. Installs what it needs when missing; idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

TARGET="${CARGO_TARGET_DIR:-target}"
WORK=target/octomap-check
VENV=target/ros-venv
CELL=0.1
CHECK="$TARGET/octomap/check_octomap"

step "liboctomap-dev, g++ and pkg-config"
ensure_octomap

step "Python reader (mcap, mcap-ros2-support; installed as for scripts/ros.sh) in $VENV"
ensure_ros_venv "$VENV"
"$VENV/bin/python" -c 'import mcap, mcap_ros2; print("mcap", mcap.__version__, "mcap-ros2-support", mcap_ros2.__version__)'


step "the checker: check_octomap.cpp against liboctomap ($CHECK)"
build_octomap_program scripts/octomap/check_octomap.cpp "$CHECK"

step "a synthetic map at $CELL m and its exports (.bt, .ot, map bag)"
# The dev profile shares its build with the rest of the test command (see scripts/ros.sh).
cargo build -q --workspace --bin sndt --example octomap_check
SNDT="$TARGET/debug/sndt"
COMPARE="$TARGET/debug/examples/octomap_check"
rm -rf "$WORK" && mkdir -p "$WORK"
"$SNDT" map synthetic:1:8 --cell "$CELL" --save-maps --out "$WORK/map" >/dev/null
map=$(find "$WORK/map/maps" -name '*.sndt' | head -n 1)
"$SNDT" export "$map" --octomap "$WORK/map.bt" --mcap "$WORK/map.mcap"
"$SNDT" export "$map" --octomap "$WORK/map.ot"

step "the bag's /octomap_binary, decoded by Python: the .bt's tree"
"$VENV/bin/python" scripts/octomap/bag_octomap.py "$WORK/map.mcap" "$WORK/map.bt" "$CELL" \
    "$WORK/msg.data"

step "liboctomap reads each and re-encodes its leaves; sndt queries its map at every leaf"
for kind in bt ot msg; do
    case $kind in
    bt) file="$WORK/map.bt" ;;
    ot) file="$WORK/map.ot" ;;
    msg) file="$WORK/msg.data" ;;
    esac
    # liboctomap's progress notes go to stderr without line ends: shown only on failure.
    if ! "$CHECK" "$kind" "$file" "$CELL" "$WORK/leaves-$kind.txt" 2>"$WORK/check-$kind.err"; then
        cat "$WORK/check-$kind.err" >&2
        exit 1
    fi
    "$COMPARE" "$map" "$WORK/leaves-$kind.txt"
done
echo "octomap: ok"
