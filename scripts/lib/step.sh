# shellcheck shell=bash
# The banner every script prints before each of its steps: `==> TEXT (at N s)`. Source it
# (`. scripts/lib/step.sh`) and call `step TEXT`.
#
# N counts the seconds since the outermost script started, not since this one did: the
# scripts that scripts/test.sh runs inherit its start, so every banner of a test run is on
# the run's one clock and a slow step shows wherever it is. Run alone, a script counts from
# its own start.
: "${SNDT_STEPS_START:=$EPOCHSECONDS}"
export SNDT_STEPS_START

# step TEXT...: a blank line, then the banner.
step() { printf '\n==> %s (at %d s)\n' "$*" $((EPOCHSECONDS - SNDT_STEPS_START)); }
