# shellcheck shell=bash
# Clippy's lints as part of the builds, so that each crate is compiled once. Source it
# (`. scripts/lib/lint.sh`) and call `lint_in_builds`.
#
# `cargo clippy` is `cargo check` with clippy-driver as RUSTC_WORKSPACE_WRAPPER: the
# workspace's own crates go through clippy-driver, dependencies through rustc. A check
# compiles every dependency a second time (as metadata only, in its own units), which cost
# the test command over five minutes. clippy-driver is a whole compiler, so with the same
# wrapper a `cargo build` or `cargo test` lints the workspace's crates while it builds them,
# and the dependencies it compiles are the ones every other build shares. CLIPPY_ARGS is how
# `cargo clippy -- -D warnings` hands its arguments to clippy-driver; clippy-driver records
# it in the dep-info, so a change rebuilds. The lints are the ones `cargo clippy
# --all-targets -- -D warnings` reports.
#
# `cargo install` makes the installed crate a workspace of its own, so it would be linted
# too: run it through `without_lints`.
lint_in_builds() {
    local driver
    rustup component add clippy >/dev/null 2>&1 || true
    driver=$(rustup which clippy-driver 2>/dev/null || command -v clippy-driver) || {
        echo "error: clippy-driver not found (rustup component add clippy)" >&2
        return 1
    }
    export RUSTC_WORKSPACE_WRAPPER="$driver"
    export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"
}

# without_lints COMMAND...: runs COMMAND without the wrapper (for `cargo install`).
without_lints() {
    env -u RUSTC_WORKSPACE_WRAPPER -u CLIPPY_ARGS "$@"
}
