#!/usr/bin/env bash
# Runs the position walk of configs/walk_soft_ground_position_tilt.toml (sink compensation, sole-tilt
# feed-forward 0.1) on the six grounds of [Romualdi 2022, Table 8.1], one at a time, with the controller's
# ground stiffness matched to the simulator's and the TOML lines given appended (keys of
# `[simplified.foot_admittance]` first, then any other section), and prints one line per ground: the command
# behind the tables of docs/soft-ground.md, "Position control: the IK on the tilted sole".
#
#   cargo build --release
#   bash tools/scenarios/soft-ground-position.sh 'touchdown_search_speed = 0.1
#   swing_tilt_gain = 1.0'
#   bash tools/scenarios/soft-ground-position.sh 'touchdown_search_speed = 0.1' '[simplified.step_adjustment]
#   enabled = true
#   dcm_error_cutoff = 2.0'
#
# GROUNDS: `k,b` pairs (default the six of Table 8.1); DURATION: seconds simulated (default 10). Logs go
# to a temporary folder (STRIDE_LOG_DIR to keep them). Columns: k, b, outcome, simulated time (the fall's),
# walked distance.
set -euo pipefail
cd "$(dirname "$0")/../.."
root="$(pwd)"
stride=target/release/stride
out="${STRIDE_LOG_DIR:-$(mktemp -d)}"
admittance="${1:-}"
extra="${2:-}"
for ground in ${GROUNDS:-8e5,1e3 8e5,1e4 1e6,1e3 1e6,1e4 2e6,1e3 2e6,1e4}; do
    k="${ground%,*}"
    b="${ground#*,}"
    overlay="$out/position-$k-$b.toml"
    cat > "$overlay" <<EOT
include = ["$root/configs/walk_soft_ground_position_tilt.toml"]
[sim.contact]
normal_stiffness = $k
normal_damping = $b
[simplified.foot_admittance]
ground_stiffness = $k
$admittance
$extra
EOT
    summary="$("$stride" run "$overlay" --duration "${DURATION:-10}" --no-progress -o "$out/position-$k-$b.mcap" 2>&1 || true)"
    outcome="$(grep -m1 '^scenario' <<< "$summary" | sed 's/.*plant: //')"
    time="$(grep -m1 'simulated' <<< "$summary" | awk '{print $2}')"
    walked="$(grep -m1 '  walked' <<< "$summary" | awk '{print $2}')"
    echo "$k $b | $outcome | $time s | $walked m"
done
