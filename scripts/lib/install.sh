# shellcheck shell=bash
# What the scripts need besides Rust, installed when missing: Debian packages, rustup
# targets, cargo-installed tools and the Python venvs. Every function is idempotent and
# costs no more than a look-up when everything is present. Source it
# (`. scripts/lib/install.sh`) from the repository root.

# `cargo install` must run without the lint wrapper (without_lints).
# shellcheck source=scripts/lib/lint.sh
. "${BASH_SOURCE[0]%/*}/lint.sh"

# apt-get install of the Debian packages given, as root or through sudo.
apt_install() {
    local sudo=() packages=("$@") downgrade=()
    if [ "$(id -u)" -ne 0 ]; then sudo=(sudo); fi
    export DEBIAN_FRONTEND=noninteractive
    # Another apt-get (a script of a parallel run) holds dpkg's lock until it has finished:
    # wait for it rather than fail.
    local wait=(-o DPkg::Lock::Timeout=600)
    echo "apt-get install ${packages[*]}"
    "${sudo[@]}" apt-get "${wait[@]}" update -qq
    # The image may ship qemu-utils from bookworm-backports, which bookworm's qemu-system-arm
    # conflicts with: when apt would remove it, bookworm's qemu-utils installed in the same
    # command keeps qemu-img.
    if apt-get install -s --no-install-recommends "${packages[@]}" 2>/dev/null |
        grep -q '^Remv qemu-utils '; then
        packages+=(qemu-utils/bookworm)
        downgrade=(--allow-downgrades)
    fi
    "${sudo[@]}" apt-get "${wait[@]}" install -y -qq --no-install-recommends "${downgrade[@]}" \
        "${packages[@]}" >/dev/null
}

# dpkg_installed PACKAGE: whether dpkg has the Debian package installed.
dpkg_installed() {
    dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'
}

# ensure_packages SPEC...: installs, in one apt-get call, the package of every SPEC whose
# thing is missing; without a call (not even apt-get update) when nothing is. A SPEC is
#   COMMAND:PACKAGE  PACKAGE provides COMMAND, looked up on PATH (so a tool installed
#                    another way counts);
#   /PATH:PACKAGE    PACKAGE provides the file /PATH;
#   PACKAGE          asked of dpkg (a library package with no command of its own).
ensure_packages() {
    local spec thing package missing=()
    for spec in "$@"; do
        thing=${spec%%:*}
        package=${spec#*:}
        if [[ $spec != *:* ]]; then
            dpkg_installed "$package" && continue
        elif [[ $thing == /* ]]; then
            [ -e "$thing" ] && continue
        else
            command -v "$thing" >/dev/null 2>&1 && continue
        fi
        [[ " ${missing[*]} " == *" $package "* ]] || missing+=("$package")
    done
    if ((${#missing[@]})); then apt_install "${missing[@]}"; fi
}

# ensure_rust_target TRIPLE: the rustup target's standard library.
ensure_rust_target() {
    # grep without -q reads the whole list: an early exit would fail rustup's write (pipefail).
    rustup target list --installed | grep -x "$1" >/dev/null || rustup target add "$1"
}

# ensure_cargo_tool CRATE [VERSION]: CRATE's binary of the same name, `cargo install`ed when
# missing or, with VERSION, when `CRATE --version` does not print "CRATE VERSION".
ensure_cargo_tool() {
    local crate=$1 version=${2:-}
    if [ -z "$version" ]; then
        command -v "$crate" >/dev/null 2>&1 && return
        without_lints cargo install "$crate" --locked
    else
        [ "$("$crate" --version 2>/dev/null)" = "$crate $version" ] && return
        without_lints cargo install "$crate" --version "$version" --locked
    fi
}

# Debian's liboctomap-dev with g++ and pkg-config to build against it; prints the versions.
ensure_octomap() {
    ensure_packages liboctomap-dev g++:g++ pkg-config:pkg-config
    echo "octomap $(pkg-config --modversion octomap), $(g++ --version | head -n 1)"
}

# build_octomap_program SOURCE PROGRAM: compiles the C++ file SOURCE against liboctomap
# (warnings are errors) into PROGRAM, unless PROGRAM is newer than SOURCE.
build_octomap_program() {
    local src=$1 program=$2
    mkdir -p "$(dirname "$program")"
    if [ ! -x "$program" ] || [ "$src" -nt "$program" ]; then
        # shellcheck disable=SC2046 # pkg-config prints several flags
        g++ -O2 -std=c++17 -Wall -Wextra -Werror -o "$program" "$src" $(pkg-config --cflags --libs octomap)
    fi
    echo "built $program"
}

# venv_install VENV REQUIREMENT...: the venv VENV (python3-venv installed when python3
# cannot make one) with the pip requirements installed in it.
venv_install() {
    local venv=$1
    shift
    python3 -m venv "$venv" 2>/dev/null || { apt_install python3-venv && python3 -m venv "$venv"; }
    "$venv/bin/pip" install -q "$@"
}

# What builds the Python package (maturin, the build backend, for `pip install
# --no-build-isolation`) and what it imports (numpy), pinned.
PYTHON_PACKAGE_REQUIREMENTS=('maturin>=1.9.4,<2' 'numpy>=1.21,<3')

# The Python packages the ROS 2 checks use (the mcap reader and ROS 2 decoder, rosbags with
# its Humble type store, pypng), pinned, in the venv $1.
ensure_ros_venv() {
    if "$1/bin/python" -c 'import mcap, mcap_ros2, png, rosbags' 2>/dev/null; then
        return
    fi
    venv_install "$1" 'mcap==1.*' 'mcap-ros2-support==0.5.*' 'pypng==0.20220715.*' \
        'rosbags==0.11.*'
}

# The Python package's build and test tools, pinned, in the venv $1: its build requirements,
# pytest and pypng (the tests read the command line's PNGs with it), matplotlib (the
# example).
ensure_python_venv() {
    if "$1/bin/python" -c 'import numpy, pytest, png, matplotlib' 2>/dev/null &&
        [ -x "$1/bin/maturin" ]; then
        return
    fi
    venv_install "$1" "${PYTHON_PACKAGE_REQUIREMENTS[@]}" 'pytest==8.*' \
        'pypng==0.20220715.*' 'matplotlib==3.*'
}

# The Python benchmark's venv $1: the package's build requirements and pyoctomap (PyPI), the
# peer it is timed against.
ensure_python_bench_venv() {
    if "$1/bin/python" -c 'import numpy, pyoctomap' 2>/dev/null && [ -x "$1/bin/maturin" ]; then
        return
    fi
    venv_install "$1" "${PYTHON_PACKAGE_REQUIREMENTS[@]}" 'pyoctomap==1.2.*'
}
