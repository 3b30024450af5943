#!/usr/bin/env bash
# The energetic cost at the thesis's 0.212 m/s against the step timing (issue 15; docs/gait.md, "Energy at the
# thesis's speed"): for each shortest step duration T, steps of f = 0.262·T m forward (the planner's reference
# speed 0.9·0.9·f/T = 0.212 m/s; docs/planner.md), nominal 1.2·T, longest 1.6·T, in both control modes, on
# walk_thesis_speed(.toml|_torque.toml). Prints one markdown table row per timing.
#
#   cargo build --release
#   bash tools/scenarios/step-timing.sh [T ...]        # default: 0.5 0.55 0.6 0.65 0.7 0.8
set -euo pipefail
cd "$(dirname "$0")/../.."
stride="$PWD/target/release/stride"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
timings=("$@")
[ "${#timings[@]}" -gt 0 ] || timings=(0.5 0.55 0.6 0.65 0.7 0.8)
figures() { # scenario file → "steady speed | c_et | DCM RMS"
    "$stride" run "$1" --no-progress --output "$work/run.mcap" 2>&1 | awk '
        /^scenario / { sub(/^[^:]*: /, ""); outcome = $0 }
        /steady forward speed/ { speed = $4 }
        /energetic cost/ { for (i = 1; i <= NF; i++) if ($i == "c_et") cost = $(i + 1) }
        /^    DCM / { dcm = $2 }
        END { printf "%s | %s | %s | %s", outcome, speed, cost, dcm }'
}
echo "| T [s] | f [m] | position: outcome | speed [m/s] | c_et [J/kg/m] | DCM RMS [mm] | torque: outcome | speed [m/s] | c_et [J/kg/m] | DCM RMS [mm] |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for t in "${timings[@]}"; do
    row="$(awk -v t="$t" 'BEGIN { f = 0.262 * t; printf "%.4f %.4f %.3f %.3f", f, sqrt(f * f + 0.15 * 0.15), 1.2 * t, 1.6 * t }')"
    read -r f distance nominal longest <<<"$row"
    cells=()
    for mode in "" _torque; do
        cat >"$work/s.toml" <<TOML
include = ["$PWD/configs/walk_thesis_speed$mode.toml"]
[planner]
feet_distance_max = $distance
step_duration_min = $t
step_duration_nominal = $nominal
step_duration_max = $longest
TOML
        cells+=("$(figures "$work/s.toml")")
    done
    echo "| $t | $f | ${cells[0]} | ${cells[1]} |"
done
