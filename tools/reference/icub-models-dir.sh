#!/usr/bin/env bash
# Install the `icub-models` package (only that one, pinned) and print the directory that holds
# `<ModelName>/model.urdf` for every official iCub model, for the stride-model reference tests:
#
#     export STRIDE_ICUB_MODELS_DIR=$(bash tools/reference/icub-models-dir.sh)
#
# The package goes into a private virtual environment (default: $HOME/.cache/stride/icub-models-venv,
# override with STRIDE_ICUB_VENV). Progress goes to stderr; stdout carries only the path.
set -euo pipefail
version="3.2.0"
venv="${STRIDE_ICUB_VENV:-${HOME:-/tmp}/.cache/stride/icub-models-venv}"
python="${PYTHON:-python3}"
if ! command -v "$python" >/dev/null 2>&1; then
  echo "icub-models-dir.sh: $python not found" >&2
  exit 1
fi
if [ ! -x "$venv/bin/python" ]; then
  mkdir -p "$(dirname "$venv")"
  "$python" -m venv "$venv" >&2
fi
if ! "$venv/bin/python" -c "import importlib.metadata as m, sys; sys.exit(m.version('icub-models') != '$version')" 2>/dev/null; then
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "icub-models==$version" >&2
fi
dir=$("$venv/bin/python" -c "import icub_models; print(icub_models.get_models_path())")
if [ ! -f "$dir/iCubGazeboV2_7/model.urdf" ]; then
  echo "icub-models-dir.sh: no iCubGazeboV2_7/model.urdf under $dir" >&2
  exit 1
fi
printf '%s\n' "$dir"
