# Sourced by the *-dir.sh scripts: `pip_venv PACKAGE VERSION VENV` makes the virtual environment VENV
# (with $PYTHON, default python3) and installs PACKAGE==VERSION in it unless that version is there.
# Progress goes to stderr.
pip_venv() {
  local package="$1" version="$2" venv="$3" python="${PYTHON:-python3}"
  if ! command -v "$python" >/dev/null 2>&1; then
    echo "$(basename "$0"): $python not found" >&2
    exit 1
  fi
  if [ ! -x "$venv/bin/python" ]; then
    mkdir -p "$(dirname "$venv")"
    "$python" -m venv "$venv" >&2
  fi
  if ! "$venv/bin/python" -c "import importlib.metadata as m, sys; sys.exit(m.version('$package') != '$version')" 2>/dev/null; then
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "$package==$version" >&2
  fi
}
