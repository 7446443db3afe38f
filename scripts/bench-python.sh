#!/usr/bin/env bash
# Opt-in benchmark of the Python package (docs/PYTHON.md, "Speed"): the map update driven
# from Python against the same update in Rust, and against pyoctomap's insertPointCloud, on
# the same frames at 10 cm, one thread. Release builds.
#
#   1. `pip install ./python` (release: what a user gets) into its own venv with numpy and
#      pyoctomap (PyPI), timed;
#   2. Rust: `sndt map synthetic:1:$FRAMES --cell 0.1` (release) prints the mean update time
#      per frame of the same frames (timed around each frame's update, one thread);
#   3. Python: python/bench/bench_update.py, $RUNS runs alternating sndt and pyoctomap.
#
# FRAMES (default 12) and RUNS (default 5) set the size; about 10 minutes with the build.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

FRAMES="${FRAMES:-12}"
RUNS="${RUNS:-5}"
TARGET="${CARGO_TARGET_DIR:-$PWD/target}"
VENV="$TARGET/python-bench-venv"

step "venv with maturin, numpy, pyoctomap ($VENV)"
ensure_python_bench_venv "$VENV"
export PATH="$VENV/bin:$PATH"

step "pip install ./python (release)"
start=$SECONDS
pip install -q --no-build-isolation --force-reinstall --no-deps ./python
echo "release wheel built and installed in $((SECONDS - start)) s"

step "Rust: sndt map synthetic:1:$FRAMES --cell 0.1 (release), mean update per frame"
cargo build -q --release -p sndt-host --bin sndt
for r in $(seq "$RUNS"); do
    "$TARGET/release/sndt" map "synthetic:1:$FRAMES" --cell 0.1 --out "$TARGET/bench-python/map" |
        grep -E 'ms/frame' | sed 's/^ */  run '"$r"': /'
done

step "Python: sndt.Map.integrate and pyoctomap.OcTree.insertPointCloud, $RUNS runs"
python python/bench/bench_update.py --frames "$FRAMES" --cell 0.1 --runs "$RUNS"
echo "$(nproc) CPUs, $(git rev-parse --short HEAD)"
