# Shared by the scripts that check sndt against other implementations: idempotent installs
# of what they need. Source it (`. scripts/lib/install.sh`) from the repository root.

# apt-get install of the Debian packages given, as root or through sudo.
apt_install() {
    local sudo=()
    if [ "$(id -u)" -ne 0 ]; then sudo=(sudo); fi
    export DEBIAN_FRONTEND=noninteractive
    "${sudo[@]}" apt-get update -qq
    "${sudo[@]}" apt-get install -y -qq --no-install-recommends "$@" >/dev/null
}

# Debian's liboctomap-dev with g++ and pkg-config to build against it; prints the versions.
ensure_octomap() {
    local missing=()
    dpkg-query -W -f='${Status}' liboctomap-dev 2>/dev/null | grep -q 'install ok installed' ||
        missing+=(liboctomap-dev)
    command -v g++ >/dev/null 2>&1 || missing+=(g++)
    command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)
    if ((${#missing[@]})); then apt_install "${missing[@]}"; fi
    echo "octomap $(pkg-config --modversion octomap), $(g++ --version | head -n 1)"
}

# The Python packages the ROS 2 checks use (the mcap reader and ROS 2 decoder, rosbags with
# its Humble type store, pypng), pinned, in the venv $1.
ensure_ros_venv() {
    local venv="$1"
    if "$venv/bin/python" -c 'import mcap, mcap_ros2, png, rosbags' 2>/dev/null; then
        return
    fi
    python3 -m venv "$venv" 2>/dev/null || { apt_install python3-venv && python3 -m venv "$venv"; }
    "$venv/bin/pip" install -q 'mcap==1.*' 'mcap-ros2-support==0.5.*' 'pypng==0.20220715.*' \
        'rosbags==0.11.*'
}

# The Python package's build and test tools, pinned, in the venv $1: maturin (the build
# backend, for `pip install --no-build-isolation`), numpy, pytest and pypng (the tests read
# the command line's PNGs with it), matplotlib (the example).
ensure_python_venv() {
    local venv="$1"
    if "$venv/bin/python" -c 'import numpy, pytest, png, matplotlib' 2>/dev/null &&
        [ -x "$venv/bin/maturin" ]; then
        return
    fi
    python3 -m venv "$venv" 2>/dev/null || { apt_install python3-venv && python3 -m venv "$venv"; }
    "$venv/bin/pip" install -q 'maturin>=1.9.4,<2' 'numpy>=1.21,<3' 'pytest==8.*' \
        'pypng==0.20220715.*' 'matplotlib==3.*'
}
