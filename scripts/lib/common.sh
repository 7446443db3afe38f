# shellcheck shell=bash
# What the scripts share, sourced in one line (`. scripts/lib/common.sh`) once they are in
# the repository root: the step banner (step.sh), the installers (install.sh), the lint
# wrapper for builds (lint.sh) and the test vector's CRCs with the Cortex-M4F board in QEMU
# (vector.sh). Each file only defines functions and constants.
# shellcheck source=scripts/lib/step.sh
. "${BASH_SOURCE[0]%/*}/step.sh"
# shellcheck source=scripts/lib/lint.sh
. "${BASH_SOURCE[0]%/*}/lint.sh"
# shellcheck source=scripts/lib/install.sh
. "${BASH_SOURCE[0]%/*}/install.sh"
# shellcheck source=scripts/lib/vector.sh
. "${BASH_SOURCE[0]%/*}/vector.sh"
