#!/usr/bin/env bash
# Explores the property tests with fresh random seeds, many times over.
#
# CI runs every property test with one fixed seed (PROPTEST_RNG_SEED in .ci/run), so a landing is never
# blocked by a case that a random seed happens to find. Exploration happens here instead: run it after
# touching a crate with property tests, and commit the `*.proptest-regressions` file a failure writes next to
# the test, together with the fix.
#
# usage: tools/stress/proptests.sh [ROUNDS] [CRATE ...]     (defaults: 20 rounds, every crate with property tests)
set -euo pipefail
cd "$(dirname "$0")/../.."
rounds="${1:-20}"
shift || true
crates=("$@")
if [ ${#crates[@]} -eq 0 ]; then
    crates=(stride-model stride-planner stride-qp stride-simplified)
fi
unset PROPTEST_RNG_SEED
failed=0
for crate in "${crates[@]}"; do
    dir="crates/${crate#stride-}"
    # the test binaries of this crate that contain property tests
    mapfile -t binaries < <(cargo test --release -p "$crate" --no-run --message-format=json 2>/dev/null |
        python3 -c '
import json, sys
for line in sys.stdin:
    try:
        m = json.loads(line)
    except ValueError:
        continue
    if m.get("reason") == "compiler-artifact" and m.get("executable") and m["target"]["kind"] == ["test"]:
        print(m["target"]["src_path"] + " " + m["executable"])
')
    for entry in "${binaries[@]}"; do
        src="${entry%% *}"
        bin="${entry#* }"
        grep -q "proptest!" "$src" || continue
        name="$crate/$(basename "$src" .rs)"
        for round in $(seq 1 "$rounds"); do
            if ! (cd "$dir" && "$bin" -q >/tmp/stride-proptest-stress.log 2>&1); then
                echo "FAILED: $name (round $round); output:"
                grep -E "minimal failing input|Test failed|panicked" /tmp/stride-proptest-stress.log | head -20
                failed=1
                break
            fi
        done
        [ "$failed" -eq 1 ] || echo "ok: $name x$rounds"
    done
done
exit "$failed"
