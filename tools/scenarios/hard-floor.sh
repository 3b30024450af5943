#!/usr/bin/env bash
# Runs a scenario on three floors (the default k 3e7 and the hard floors k 3e8, 1e9 N/m³ of docs/sim.md, b
# scaled as √k, normal and tangential) and three sensor seeds, and prints one line per run: outcome, DCM and
# feet RMS [mm], largest torso tilt [°]. The command behind docs/wbc.md's "Joint velocities" table.
#
#   bash tools/scenarios/hard-floor.sh [SCENARIO] [OVERLAY.toml] [STRIDE_BINARY]
#
# SCENARIO defaults to configs/walk_curve_fast_torque.toml; OVERLAY (optional) is merged on top of each run,
# e.g. a file with `[estimation] joint_velocity_bandwidth = 0.0` for the encoders' velocities.
set -euo pipefail
cd "$(dirname "$0")/../.."
scenario="$(realpath "${1:-configs/walk_curve_fast_torque.toml}")"
overlay="${2:-}"
stride="${3:-target/release/stride}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
for floor in 3e7:3e5 3e8:9.5e5 1e9:1.7e6; do
    k="${floor%:*}"
    b="${floor#*:}"
    for seed in 0 1 2; do
        f="$out/run.toml"
        {
            printf 'include = ["%s"%s]\n' "$scenario" "${overlay:+, \"$(realpath "$overlay")\"}"
            printf '[sim.contact]\nnormal_stiffness = %s\nnormal_damping = %s\n' "$k" "$b"
            printf 'tangential_stiffness = %s\ntangential_damping = %s\n' "$k" "$b"
            printf '[sim.sensors]\nseed = %s\n' "$seed"
        } > "$f"
        "$stride" run "$f" --no-progress --output "$out/run.mcap" > "$out/summary.txt" 2>&1 || true
        outcome="$(head -1 "$out/summary.txt" | sed 's/.*plant: //')"
        dcm="$(awk '$1 == "DCM" {print $2}' "$out/summary.txt")"
        feet="$(awk '$1 == "feet" {print $2}' "$out/summary.txt")"
        tilt="$(grep -o 'largest torso tilt [0-9.]*' "$out/summary.txt" | awk '{print $4}')"
        echo "k $k seed $seed: $outcome | DCM $dcm | feet $feet | tilt $tilt"
    done
done
