#!/usr/bin/env bash
# Install the `example-robot-data` package (only that one, pinned) and print its `robots` directory
# (`g1_description/`, `talos_data/`, ...), for the tests that try stride on robots nobody configured:
#
#     export STRIDE_EXAMPLE_ROBOT_DATA_DIR=$(bash tools/reference/example-robot-data-dir.sh)
#
# The package goes into a private virtual environment (default:
# $HOME/.cache/stride/example-robot-data-venv, override with STRIDE_EXAMPLE_ROBOT_DATA_VENV). Progress goes
# to stderr; stdout carries only the path. The URDFs are never committed.
set -euo pipefail
version="6.0.0"
venv="${STRIDE_EXAMPLE_ROBOT_DATA_VENV:-${HOME:-/tmp}/.cache/stride/example-robot-data-venv}"
. "$(dirname "$0")/pip-venv.sh"
pip_venv example-robot-data "$version" "$venv"
dir=$("$venv/bin/python" -c "import sysconfig, os; print(os.path.join(sysconfig.get_paths()['purelib'], 'cmeel.prefix', 'share', 'example-robot-data', 'robots'))")
if [ ! -f "$dir/g1_description/urdf/g1_29dof_rev_1_0.urdf" ]; then
  echo "example-robot-data-dir.sh: no g1_description/urdf/g1_29dof_rev_1_0.urdf under $dir" >&2
  exit 1
fi
printf '%s\n' "$dir"
