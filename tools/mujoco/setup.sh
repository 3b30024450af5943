#!/usr/bin/env bash
# Fetch MuJoCo 3.17.0's shared library from its PyPI wheel (the only network it uses is PyPI) and print the
# folder that holds it, for the `mujoco` feature of stride (crate mujoco-rs 7.0.0+mj-3.17.0, which checks
# at start-up that the library is exactly 3.17.0):
#
#     MUJOCO_DYNAMIC_LINK_DIR=$(bash tools/mujoco/setup.sh) cargo build --release --features mujoco
#
# The folder (default $HOME/.cache/stride/mujoco-3.17.0/lib, override with STRIDE_MUJOCO_DIR) gets
# `libmujoco.so.3.17.0` and the unversioned `libmujoco.so` link the crate's build script looks for; the
# build bakes the folder into the binary's rpath (see build.rs of stride-mujoco), so no LD_LIBRARY_PATH is
# needed at run time. Progress goes to stderr; stdout carries only the path.
set -euo pipefail
version="3.17.0"
dir="${STRIDE_MUJOCO_DIR:-${HOME:-/tmp}/.cache/stride/mujoco-$version}"
lib="$dir/lib"
python="${PYTHON:-python3}"
if [ ! -f "$lib/libmujoco.so.$version" ]; then
  if ! command -v "$python" >/dev/null 2>&1; then
    echo "mujoco/setup.sh: $python not found (needed for pip download)" >&2
    exit 1
  fi
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  echo "mujoco/setup.sh: downloading the mujoco==$version wheel from PyPI" >&2
  "$python" -m pip download --quiet --disable-pip-version-check --no-deps --only-binary=:all: \
    --dest "$tmp" "mujoco==$version" >&2
  wheel=$(ls "$tmp"/mujoco-"$version"-*.whl | head -n 1)
  "$python" - "$wheel" "$tmp/x" <<'PY'
import sys, zipfile
with zipfile.ZipFile(sys.argv[1]) as z:
    for name in z.namelist():
        if name.startswith("mujoco/libmujoco.so") or name.startswith("mujoco/include/"):
            z.extract(name, sys.argv[2])
PY
  mkdir -p "$lib" "$dir/include"
  cp "$tmp/x/mujoco/libmujoco.so.$version" "$lib/"
  cp -r "$tmp/x/mujoco/include/." "$dir/include/"
fi
ln -sf "libmujoco.so.$version" "$lib/libmujoco.so"
printf '%s\n' "$lib"
