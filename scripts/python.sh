#!/usr/bin/env bash
# The Python package (python/, docs/PYTHON.md): `pip install ./python` into a local venv,
# then pytest against the `sndt` command line, the package's doctests, and the example
# without a display. Installs what it needs (a venv with maturin, numpy, pytest, pypng,
# matplotlib); idempotent.
#
# The wheel is built with cargo's dev profile (MATURIN_PEP517_ARGS), so it shares the
# compiled sndt-core and sndt-host with `cargo test`; `pip install ./python` without it
# builds in release, as a user gets it.
#
# That build is also where the package's crate is linted (clippy -D warnings inside the
# build, scripts/lib/lint.sh): the workspace's build step leaves it to this one.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh
lint_in_builds

TARGET="${CARGO_TARGET_DIR:-$PWD/target}"
VENV="$TARGET/python-venv"

step "venv with maturin, numpy, pytest, pypng, matplotlib ($VENV)"
ensure_python_venv "$VENV"
# The build backend runs the venv's `maturin` executable from PATH.
export PATH="$VENV/bin:$PATH"
python --version

step "pip install ./python (the wheel, dev profile)"
start=$SECONDS
MATURIN_PEP517_ARGS="--profile dev" pip install -q --no-build-isolation \
    --force-reinstall --no-deps ./python
echo "wheel built and installed in $((SECONDS - start)) s"

step "the sndt command line the tests compare with"
cargo build -q --workspace --bin sndt
export SNDT_BIN="$TARGET/debug/sndt"

step "pytest python/tests, and the package's doctests"
# From the repository root: run from python/, its sndt/ sources would shadow the package.
python -m pytest -q -p no:cacheprovider python/tests
python -m pytest -q -p no:cacheprovider --doctest-modules --pyargs sndt

step "examples/python/map_synthetic.py (no display)"
MPLBACKEND=Agg python examples/python/map_synthetic.py --dataset synthetic:1:100 \
    --every 10 --out "$TARGET/python-example"
test -s "$TARGET/python-example/view.png"
