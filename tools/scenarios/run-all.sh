#!/usr/bin/env bash
# Runs every shipped scenario with the release binary and prints each end-of-run summary: the command behind
# the scenario tables of docs/runner.md and README.md.
#
#   bash tools/scenarios/run-all.sh [STRIDE_BINARY] [OUT_DIR]
#
# The iCub scenarios run when STRIDE_ICUB_MODELS_DIR is set (`bash tools/reference/icub-models-dir.sh`
# prints the folder). Logs go to OUT_DIR (default: a temporary folder).
set -euo pipefail
cd "$(dirname "$0")/../.."
stride="${1:-target/release/stride}"
out="${2:-$(mktemp -d)}"
if [ "$stride" = "target/release/stride" ]; then
    cargo build --release --quiet --bin stride
fi
scenarios=(walk_straight walk_straight_mpc walk_straight_torque turn_in_place walk_curve stand_push walk_velocity)
if [ -n "${STRIDE_ICUB_MODELS_DIR:-}" ]; then
    scenarios+=(walk_straight_icub walk_straight_icub_torque)
fi
for s in "${scenarios[@]}"; do
    "$stride" run "configs/$s.toml" --output "$out/$s.mcap"
    echo
done
