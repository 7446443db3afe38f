#!/usr/bin/env bash
# Opt-in peer benchmark: the S-NDT map update beside OctoMap's OcTree update on the same
# points, for cell sizes of 5, 10 and 20 cm. Prints one Markdown table of ms/frame
# (median of 12 frames, min-max in parentheses) and the ratio sndt / OctoMap.
#
# Both sides: the same 12 consecutive 1024x768 frames of the synthetic living room
# (`sndt synth --scenes 1 --frames-per-scene 12 --no-predictions`), the same world points
# (`sndt points` exports exactly what the core integrates), max range 20 m, the same cell size,
# one thread pinned to the same CPU, a warm-up pass then a timed pass, only the map
# update inside the clock (no I/O, no evaluation). sndt: `integrate_depth` with
# ground-truth labels (statistics, classes and free space), host/benches/peers.rs.
# OctoMap: `OcTree::insertPointCloud(cloud, origin, 20, lazy_eval false, discretize
# true)`, scripts/peers/octomap_bench.cpp against Debian's liboctomap-dev.
#
# Installs liboctomap-dev (and g++, pkg-config) with apt-get when missing; reuses the
# frames under $CARGO_TARGET_DIR/peers (default target/peers) when present.
#
# RUNS=N (default 1) repeats both sides N times, alternating, and adds the ratio of every
# run; the ms columns are then the median of the runs' medians (min-max over all frames)
# and the ratio column is the median ratio. OctoMap's median moves by 20 % or more from
# run to run at 5 cm, so one run says little there.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

FRAMES=12
CELLS=(0.05 0.10 0.20)
RUNS="${RUNS:-1}"
if ! [[ "$RUNS" =~ ^[1-9][0-9]*$ ]]; then
    echo "error: RUNS must be a positive integer, got '$RUNS'" >&2
    exit 2
fi
# Absolute: cargo runs the bench binary from the package's directory.
WORK="$(realpath -m "${CARGO_TARGET_DIR:-target}/peers")"
DATA="$WORK/living-room"
POINTS="$WORK/points.bin"
HARNESS_SRC=scripts/peers/octomap_bench.cpp
HARNESS="$WORK/octomap_bench"
# Before anything runs: the CPUs (nproc would count OMP_NUM_THREADS) and the load.
CPUS=$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)
LOAD=$(cut -d' ' -f1 /proc/loadavg)

step "OctoMap, g++ and pkg-config"
ensure_octomap

step "frames: synthetic living room, $FRAMES frames ($DATA)"
mkdir -p "$WORK"
if [ -f "$DATA/test.txt" ] && [ "$(wc -l <"$DATA/test.txt")" -eq "$FRAMES" ]; then
    echo "present, reused"
else
    rm -rf "$DATA"
    cargo run --release --quiet -p sndt-host --bin sndt -- \
        synth --out "$DATA" --scenes 1 --frames-per-scene "$FRAMES" --no-predictions
fi

step "world points for OctoMap ($POINTS)"
cargo run --release --quiet -p sndt-host --bin sndt -- \
    points "$DATA" --points-file "$POINTS" --frames "$FRAMES"

step "OctoMap harness ($HARNESS)"
if [ ! -x "$HARNESS" ] || [ "$HARNESS_SRC" -nt "$HARNESS" ]; then
    # shellcheck disable=SC2046 # pkg-config prints several flags
    g++ -O2 -std=c++17 -o "$HARNESS" "$HARNESS_SRC" $(pkg-config --cflags --libs octomap)
fi
echo "built"

# One thread on the same CPU for both sides; OMP_NUM_THREADS=1 in case the library was
# built with OpenMP (Debian's is not).
pin=()
if command -v taskset >/dev/null 2>&1; then pin=(taskset -c "$((CPUS - 1))"); fi

cargo bench --quiet -p sndt-host --bench peers --no-run
sndt_runs=()
octo_runs=()
for ((run = 1; run <= RUNS; run++)); do
    step "sndt (cargo bench -p sndt-host --bench peers), run $run of $RUNS"
    out="$("${pin[@]}" cargo bench --quiet -p sndt-host --bench peers -- "$DATA" "$FRAMES")"
    echo "$out"
    sndt_runs+=("$out")
    step "OctoMap ($HARNESS), run $run of $RUNS"
    out="$(OMP_NUM_THREADS=1 "${pin[@]}" "$HARNESS" "$POINTS" "${CELLS[@]}")"
    echo "$out"
    octo_runs+=("$out")
done
sndt_out="${sndt_runs[0]}"

# The value of `key=` on the line of `side` for cell size `cell`.
field() { awk -v s="$1" -v c="cell=$2" -v k="$3=" '$1 == s && $2 == c { for (i = 3; i <= NF; i++) if (index($i, k) == 1) print substr($i, length(k) + 1) }'; }

# Per run, one line "sndt_median sndt_min sndt_max octomap_median octomap_min octomap_max"
# for cell size `cell`.
run_lines() {
    local cell=$1 r
    for ((r = 0; r < RUNS; r++)); do
        local v=()
        for k in median_ms min_ms max_ms; do v+=("$(field sndt "$cell" "$k" <<<"${sndt_runs[$r]}")"); done
        for k in median_ms min_ms max_ms; do v+=("$(field octomap "$cell" "$k" <<<"${octo_runs[$r]}")"); done
        for x in "${v[@]}"; do
            if [ -z "$x" ]; then
                echo "missing result for cell $cell in run $((r + 1))" >&2
                exit 1
            fi
        done
        echo "${v[*]}"
    done
}

step "result"
echo
if ((RUNS == 1)); then
    echo "| cell | sndt ms/frame | OctoMap ms/frame | sndt / OctoMap |"
    echo "|---|---|---|---|"
else
    echo "| cell | sndt ms/frame | OctoMap ms/frame | sndt / OctoMap (median of $RUNS runs) | per run |"
    echo "|---|---|---|---|---|"
fi
for cell in "${CELLS[@]}"; do
    lines="$(run_lines "$cell")"
    awk -v c="$cell" -v runs="$RUNS" '
        function median(a, n,    i, j, t) {
            for (i = 2; i <= n; i++) for (j = i; j > 1 && a[j - 1] > a[j]; j--) { t = a[j]; a[j] = a[j - 1]; a[j - 1] = t }
            return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
        }
        {
            n++; sm[n] = $1; om[n] = $4; ratio[n] = $1 / $4; per = per (n > 1 ? ", " : "") sprintf("%.3f", $1 / $4)
            if (n == 1 || $2 < sl) sl = $2; if (n == 1 || $3 > sh) sh = $3
            if (n == 1 || $5 < ol) ol = $5; if (n == 1 || $6 > oh) oh = $6
        }
        END {
            s = median(sm, n); o = median(om, n); r = median(ratio, n)
            line = sprintf("| %g cm | %.1f (%.1f-%.1f) | %.1f (%.1f-%.1f) | %.3f |", c * 100, s, sl, sh, o, ol, oh, r)
            if (runs > 1) line = line " " per " |"
            print line
        }' <<<"$lines"
done
echo
cpu=$(awk -F': *' '/^model name/ { print $2; exit }' /proc/cpuinfo)
commit=$(git rev-parse --short HEAD)
if ! git diff --quiet HEAD 2>/dev/null; then commit="$commit (working tree modified)"; fi
echo "$FRAMES frames of $(awk '$1 == "sndt" && $2 ~ /^frames=/ { sub("pixels=", "", $3); print $3 }' <<<"$sndt_out") pixels, median of $FRAMES (min-max), $RUNS run(s), one thread;" \
    "machine: $CPUS CPUs (nproc), ${cpu:-unknown CPU}, load average $LOAD before the runs; commit $commit"
