#!/usr/bin/env bash
# Builds the wheel from this checkout with pip (scikit-build-core, pyproject.toml), installs it in a
# fresh virtual environment and runs the pytest suite against the installed package, from outside the
# checkout so that nothing but the wheel can be imported. Needs PyPI (build requirements, numpy, pytest).
# Usage: scripts/python-wheel-test.sh [PYTHON] [WORK_DIR]
set -euo pipefail
python=${1:-python3}
root=$(cd "$(dirname "$0")/.." && pwd)
work=${2:-$root/build/wheel-test}
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)

"$python" -m venv "$work/venv"
venv_python="$work/venv/bin/python"
echo "python-wheel-test: building the wheel"
"$venv_python" -m pip wheel --quiet --no-deps --wheel-dir "$work/dist" "$root"
wheel=$(ls "$work"/dist/occ_improve-*.whl)
echo "python-wheel-test: installing $(basename "$wheel") in a fresh venv"
"$venv_python" -m pip install --quiet "$wheel" pytest pillow

cd "$work"
installed=$("$venv_python" -c "import occ_improve; print(occ_improve.__file__)")
case "$installed" in
  "$work"/venv/*) echo "python-wheel-test: imported $installed" ;;
  *) echo "python-wheel-test: imported $installed, not the installed wheel" >&2; exit 1 ;;
esac
PYTHONDONTWRITEBYTECODE=1 "$venv_python" -m pytest -q -rs -p no:cacheprovider "$root/tests/python"
echo "python-wheel-test: passed"
