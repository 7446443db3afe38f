#!/usr/bin/env bash
# Opt-in benchmark: peak memory and throughput of `sndt map` on long ROS 2 bags, against
# the prepared layout holding the same frames.
#
# For each size in SIZES (default "1G 8G"; M for megabytes, e.g. "100M" for a quick run),
# `sndt synth` renders one trajectory through the synthetic living room with as many
# 1024x768 frames as fill that many bytes
# as an uncompressed bag (as `ros2 bag record` writes by default: 2.36 MB of 16UC1 depth
# and mono8 labels per frame), and writes the same frames in the prepared layout. Then
# `sndt map` maps each at 10 cm (release build), under GNU time for the peak RSS. The
# table gives the bag's size, the frames, and per input the peak RSS and frames per second
# (wall clock, opening included). The bags are written just before they are mapped, so
# they are read from the page cache.
#
# Needs about 1.1 x the sizes in free disk under $OUT (default target/bench-bags) and
# takes about 50 minutes for "1G 8G" on 2 cores; KEEP=1 keeps the bags for another run.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

SIZES="${SIZES:-1G 8G}"
OUT="${OUT:-${CARGO_TARGET_DIR:-target}/bench-bags}"
# Bytes one frame takes in an uncompressed bag: depth 1024 x 768 x 2, labels 1024 x 768,
# plus camera info, transforms and record headers (measured: about 1.1 kB).
FRAME_BYTES=2360400

step "GNU time (for the peak RSS)"
ensure_packages /usr/bin/time:time

step "release build"
cargo build --release -q -p sndt-host --bin sndt
SNDT="${CARGO_TARGET_DIR:-target}/release/sndt"
mkdir -p "$OUT"

# Runs `sndt map` on $1 under GNU time; prints "<peak RSS MiB> <frames per second>".
measure() {
    local input="$1" log="$OUT/map.log"
    /usr/bin/time -v "$SNDT" map "$input" --cell 0.1 --out "$OUT/map-out" >"$log" 2>&1
    local rss wall frames
    rss=$(awk -F': ' '/Maximum resident set size/ { print $2 }' "$log")
    wall=$(awk -F': ' '/Elapsed \(wall clock\)/ { print $2 }' "$log" |
        awk -F: '{ s = 0; for (i = 1; i <= NF; i++) s = s * 60 + $i; print s }')
    frames=$(awk '/frames mapped,/ { print $1 }' "$log")
    awk -v r="$rss" -v w="$wall" -v f="$frames" 'BEGIN { printf "%.0f %.2f\n", r / 1024, f / w }'
}

rows=()
for spec in $SIZES; do
    case "$spec" in
    *G) bytes=$((${spec%G} * 1000000000)) ;;
    *M) bytes=$((${spec%M} * 1000000)) ;;
    *) echo "error: a size is NG or NM, got '$spec'" >&2 && exit 2 ;;
    esac
    frames=$((bytes / FRAME_BYTES + 1))
    bag="$OUT/room-$spec.mcap"
    prepared="$OUT/room-$spec"
    if [ ! -f "$bag" ] || [ ! -d "$prepared" ]; then
        step "$spec: $frames frames of the living room as a bag and in the prepared layout"
        rm -rf "$bag" "$prepared"
        "$SNDT" synth --scenes 1 --frames-per-scene "$frames" --no-predictions \
            --mcap "$bag" --mcap-compression none --out "$prepared" >/dev/null
    fi
    size=$(stat -c %s "$bag")
    step "$spec: sndt map on the bag ($size bytes), then on the prepared layout"
    read -r bag_rss bag_fps < <(measure "$bag")
    read -r prep_rss prep_fps < <(measure "$prepared")
    rows+=("| $(awk -v s="$size" 'BEGIN { printf "%.2f", s / 1e9 }') | $frames | $bag_rss | $bag_fps | $prep_rss | $prep_fps |")
    [ "${KEEP:-0}" = 1 ] || rm -rf "$bag" "$prepared"
done

step "sndt map at 10 cm: peak RSS and throughput, bag against prepared layout ($(nproc) CPUs, $(git rev-parse --short HEAD))"
echo "| bag GB | frames | bag: peak RSS MiB | bag: frames/s | prepared: peak RSS MiB | prepared: frames/s |"
echo "|---:|---:|---:|---:|---:|---:|"
printf '%s\n' "${rows[@]}"
