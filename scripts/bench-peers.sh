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
#
# VARIANTS (default "baseline") lists sndt builds to alternate with OctoMap in each run,
# each built into its own target directory:
#   baseline       no RUSTFLAGS: what any x86-64 gets; the update at the CPU's fastest
#                  level (sndt-dispatch: AVX-512, AVX2 or SSE2);
#   baseline-avx2  the same binary with the update capped at AVX2 (SNDT_LEVEL=avx2): what
#                  it runs on an AVX2 CPU without AVX-512;
#   v3             -C target-cpu=x86-64-v3 (AVX2 everywhere), the update capped at AVX2;
#   native         -C target-cpu=native.
# e.g. RUNS=5 VARIANTS="native v3 baseline baseline-avx2" bash scripts/bench-peers.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

FRAMES=12
CELLS=(0.05 0.10 0.20)
RUNS="${RUNS:-1}"
read -r -a VARIANT_LIST <<<"${VARIANTS:-baseline}"
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

# A variant's RUSTFLAGS, its target directory and its SNDT_LEVEL cap.
variant_flags() {
    case "$1" in
        baseline | baseline-avx2) echo "" ;;
        v3) echo "-C target-cpu=x86-64-v3" ;;
        native) echo "-C target-cpu=native" ;;
        *)
            echo "error: unknown variant '$1' (baseline, baseline-avx2, v3, native)" >&2
            exit 2
            ;;
    esac
}
variant_dir() { echo "$WORK/build-${1%-avx2}"; }
variant_level() { case "$1" in baseline-avx2 | v3) echo avx2 ;; *) echo avx512 ;; esac; }
for v in "${VARIANT_LIST[@]}"; do
    variant_flags "$v" >/dev/null
    step "sndt build '$v' (RUSTFLAGS='$(variant_flags "$v")')"
    RUSTFLAGS="$(variant_flags "$v")" CARGO_TARGET_DIR="$(variant_dir "$v")" \
        cargo bench --quiet -p sndt-host --bench peers --no-run
done
# sndt_runs[v * RUNS + run - 1]: the output of variant v's run.
sndt_runs=()
octo_runs=()
for ((run = 1; run <= RUNS; run++)); do
    for ((v = 0; v < ${#VARIANT_LIST[@]}; v++)); do
        name="${VARIANT_LIST[$v]}"
        step "sndt '$name' (cargo bench -p sndt-host --bench peers), run $run of $RUNS"
        out="$(RUSTFLAGS="$(variant_flags "$name")" CARGO_TARGET_DIR="$(variant_dir "$name")" \
            SNDT_LEVEL="$(variant_level "$name")" \
            "${pin[@]}" cargo bench --quiet -p sndt-host --bench peers -- "$DATA" "$FRAMES")"
        echo "$out"
        sndt_runs[v * RUNS + run - 1]="$out"
    done
    step "OctoMap ($HARNESS), run $run of $RUNS"
    out="$(OMP_NUM_THREADS=1 "${pin[@]}" "$HARNESS" "$POINTS" "${CELLS[@]}")"
    echo "$out"
    octo_runs+=("$out")
done
sndt_out="${sndt_runs[0]}"

# The value of `key=` on the line of `side` for cell size `cell`.
field() { awk -v s="$1" -v c="cell=$2" -v k="$3=" '$1 == s && $2 == c { for (i = 3; i <= NF; i++) if (index($i, k) == 1) print substr($i, length(k) + 1) }'; }

# Per run, one line "sndt_median sndt_min sndt_max octomap_median octomap_min octomap_max"
# for cell size `cell` and variant number `variant`.
run_lines() {
    local cell=$1 variant=$2 r
    for ((r = 0; r < RUNS; r++)); do
        local v=()
        for k in median_ms min_ms max_ms; do v+=("$(field sndt "$cell" "$k" <<<"${sndt_runs[variant * RUNS + r]}")"); done
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
    echo "| cell | sndt build | sndt ms/frame | OctoMap ms/frame | sndt / OctoMap |"
    echo "|---|---|---|---|---|"
else
    echo "| cell | sndt build | sndt ms/frame | OctoMap ms/frame | sndt / OctoMap (median of $RUNS runs) | per run |"
    echo "|---|---|---|---|---|---|"
fi
for cell in "${CELLS[@]}"; do
  for ((v = 0; v < ${#VARIANT_LIST[@]}; v++)); do
    lines="$(run_lines "$cell" "$v")"
    awk -v c="$cell" -v runs="$RUNS" -v build="${VARIANT_LIST[$v]}" '
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
            line = sprintf("| %g cm | %s | %.1f (%.1f-%.1f) | %.1f (%.1f-%.1f) | %.3f |", c * 100, build, s, sl, sh, o, ol, oh, r)
            if (runs > 1) line = line " " per " |"
            print line
        }' <<<"$lines"
  done
done
echo
cpu=$(awk -F': *' '/^model name/ { print $2; exit }' /proc/cpuinfo)
commit=$(git rev-parse --short HEAD)
if ! git diff --quiet HEAD 2>/dev/null; then commit="$commit (working tree modified)"; fi
echo "$FRAMES frames of $(awk '$1 == "sndt" && $2 ~ /^frames=/ { sub("pixels=", "", $3); print $3 }' <<<"$sndt_out") pixels, median of $FRAMES (min-max), $RUNS run(s), one thread;" \
    "machine: $CPUS CPUs (nproc), ${cpu:-unknown CPU}, load average $LOAD before the runs; commit $commit"
levels=""
for ((v = 0; v < ${#VARIANT_LIST[@]}; v++)); do
    level=$(awk '$1 == "sndt" && $2 ~ /^frames=/ { for (i = 3; i <= NF; i++) if ($i ~ /^level=/) print substr($i, 7) }' <<<"${sndt_runs[v * RUNS]}")
    levels="$levels ${VARIANT_LIST[$v]}=$level"
done
echo "CPU flags: $(grep -m1 -o -w -E 'avx512f|avx2' /proc/cpuinfo | sort -u | tr '\n' ' ')(of avx2, avx512f); sndt's update level per build:$levels"
