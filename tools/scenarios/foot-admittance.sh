#!/usr/bin/env bash
# Runs scenarios of configs/ on several floors, with and without the foot admittance of position control
# (configs/layers/foot_admittance.toml), and prints one markdown table row per run: the command behind the
# tables of docs/foot-admittance.md.
#
#   cargo build --release
#   FLOORS="default 3e8:9.5e5 1e9:1.7e6" bash tools/scenarios/foot-admittance.sh walk_straight layers/walk_fast_base
#
# FLOORS: `default` (the scenario's own ground) or `k:b`, a floor of normal stiffness k [N/m³] and damping
# b [N·s/m³] (the tangential stick law set to the same k and b, as docs/sim.md's stiff-floor table); default
# "default 3e8:9.5e5 1e9:1.7e6"; NORMAL_ONLY=1 sets the normal law only (the soft grounds of
# configs/sweeps/soft_ground_table_8_1_position.toml). PLANT: `simulator` (default) or `mujoco` (a `--features mujoco` build).
# ADMITTANCE: `off on` (default), `on` or `off`, the rows to run; `default` runs the scenario as it is (its
# own admittance settings, on by default), the rows of docs/sim.md's hard-floor table.
# The iCub scenarios need STRIDE_ICUB_MODELS_DIR. Logs go to a temporary folder (STRIDE_LOG_DIR to keep them).
# Columns: floor, admittance, outcome, goal distance, DCM RMS / max, ZMP RMS, largest torso tilt.
set -euo pipefail
cd "$(dirname "$0")/../.."
root="$(pwd)"
stride=target/release/stride
out="${STRIDE_LOG_DIR:-$(mktemp -d)}"
floors=(${FLOORS:-default 3e8:9.5e5 1e9:1.7e6})
plant="${PLANT:-simulator}"
echo "| scenario | floor k:b | admittance | outcome | goal dist. | DCM RMS / max | ZMP RMS | max tilt |"
echo "|---|---|---|---|---|---|---|---|"
for s in "$@"; do
    for floor in "${floors[@]}"; do
        for admittance in ${ADMITTANCE:-off on}; do
            name="${s//\//_}-${floor/:/-}-$admittance"   # layers/x -> layers_x
            overlay="$out/$name.toml"
            includes="\"$root/configs/$s.toml\""
            if [ "$admittance" = on ]; then
                includes="$includes, \"$root/configs/layers/foot_admittance.toml\""
            fi
            echo "include = [$includes]" > "$overlay"
            if [ "$admittance" = off ]; then
                # On by default in position control since 2026-12-05.
                printf '[simplified.foot_admittance]\nenabled = false\n' >> "$overlay"
            fi
            if [ "$floor" != default ]; then
                k="${floor%%:*}"
                b="${floor##*:}"
                printf '[sim.contact]\nnormal_stiffness = %s\nnormal_damping = %s\n' "$k" "$b" >> "$overlay"
                if [ -z "${NORMAL_ONLY:-}" ]; then
                    printf 'tangential_stiffness = %s\ntangential_damping = %s\n' "$k" "$b" >> "$overlay"
                fi
            fi
            summary="$("$stride" run "$overlay" --plant "$plant" --no-progress --output "$out/$name.mcap" 2>&1 || true)"
            printf '%s\n' "$summary" | awk -v s="$s" -v f="$floor" -v a="$admittance" '
                /^scenario / { sub(/^[^:]*: /, ""); outcome = $0 }
                /^Error|^error/ { outcome = $0 }
                /^  goal: / { goal = $2 " m" }
                /largest torso tilt/ { tilt = $NF }
                /^    DCM / { dcm = $2 " / " $3 " mm" }
                /^    ZMP / { zmp = $2 " mm" }
                END { printf "| %s | %s | %s | %s | %s | %s | %s | %s |\n", s, f, a, outcome, goal, dcm, zmp, tilt }'
        done
    done
done
