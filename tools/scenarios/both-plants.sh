#!/usr/bin/env bash
# Runs every scenario of configs/ (or the ones named) on stride-sim and on MuJoCo and prints one markdown
# table row per run: the command behind the side-by-side tables of docs/mujoco.md (issue 16).
#
#   MUJOCO_DYNAMIC_LINK_DIR=$(bash tools/mujoco/setup.sh) cargo build --release --features mujoco
#   bash tools/scenarios/both-plants.sh [SCENARIO ...]        # names without .toml; default: all of configs/
#
# The iCub scenarios need STRIDE_ICUB_MODELS_DIR (`bash tools/reference/icub-models-dir.sh`). Logs go to a
# temporary folder (STRIDE_LOG_DIR to keep them). Columns: outcome, goal distance, DCM RMS / max, CoM RMS,
# ZMP RMS, largest torso tilt, steady forward speed, real-time factor (wall clock: depends on the load).
set -euo pipefail
cd "$(dirname "$0")/../.."
stride=target/release/stride
out="${STRIDE_LOG_DIR:-$(mktemp -d)}"
if [ "$#" -gt 0 ]; then
    scenarios=("$@")
else
    scenarios=()
    for f in configs/*.toml; do scenarios+=("$(basename "$f" .toml)"); done
fi
echo "| scenario | plant | outcome | goal dist. | DCM RMS / max | CoM RMS | ZMP RMS | max tilt | steady speed | RTF |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for s in "${scenarios[@]}"; do
    if [[ "$s" == *icub* && -z "${STRIDE_ICUB_MODELS_DIR:-}" ]]; then
        continue
    fi
    for plant in simulator mujoco; do
        summary="$("$stride" run "configs/$s.toml" --plant "$plant" --no-progress --output "$out/$s-$plant.mcap" 2>&1 || true)"
        printf '%s\n' "$summary" | awk -v s="$s" -v p="$plant" '
            /^scenario / { sub(/^[^:]*: /, ""); outcome = $0 }
            /^Error|^error/ { outcome = $0 }
            /real time$/ { rtf = $(NF-2) }
            /^  goal: / { goal = $2 " m" }
            /largest torso tilt/ { tilt = $NF }
            /steady forward speed/ { speed = ($4 == "n/a") ? "n/a" : $4 " m/s" }
            /^    DCM / { dcm = $2 " / " $3 " mm" }
            /^    CoM / { com = $2 " mm" }
            /^    ZMP / { zmp = $2 " mm" }
            END { printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", s, p, outcome, goal, dcm, com, zmp, tilt, speed, rtf }'
    done
done
