#!/bin/bash
# Instructions and size of zstd parameters on a log's chunk records (docs/performance.md, "The log's
# compression"). Usage: bash tools/bench/log-zstd/run.sh LOG.mcap
#   LOG.mcap: e.g. `stride run configs/walk_straight.toml --duration 2 --no-progress -o /tmp/x.mcap`.
# Needs python (`$PYTHON`, default python3) with `mcap` and `zstandard`, gcc, valgrind, and libzstd.so.1 (the header is zstd-sys's).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
"${PYTHON:-python3}" "$here/extract_chunks.py" "$1" "$work/records.bin"
zstd_include=$(ls -d ~/.cargo/registry/src/*/zstd-sys-*/zstd/lib | head -1)
gcc -O2 -I"$zstd_include" "$here/zstd_chunks.c" "$(ls /usr/lib/x86_64-linux-gnu/libzstd.so.1)" -o "$work/zt"
# chunk bytes, level, literals (0 zstd's default, 1 Huffman, 2 raw), windowLog, hashLog, minMatch
for params in "524288 1" "1048576 -5 1 20 17 7" "1048576 -6 1 20 17 7" "1048576 -7 1 20 17 7" \
    "1048576 -8 1 20 17 7" "1048576 -7 1 20 17 6" "524288 -1" "1048576 -7 2 20 17 7"; do
    # shellcheck disable=SC2086
    out=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$work/zt" "$work/records.bin" $params 2>"$work/vg")
    echo "$params | $out | $(grep -o 'Collected : [0-9]*' "$work/vg" | awk '{print $3}') instructions"
done
rm -rf "$work"
