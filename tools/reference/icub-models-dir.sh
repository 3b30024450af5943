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
. "$(dirname "$0")/pip-venv.sh"
pip_venv icub-models "$version" "$venv"
dir=$("$venv/bin/python" -c "import icub_models; print(icub_models.get_models_path())")
if [ ! -f "$dir/iCubGazeboV2_7/model.urdf" ]; then
  echo "icub-models-dir.sh: no iCubGazeboV2_7/model.urdf under $dir" >&2
  exit 1
fi
printf '%s\n' "$dir"
