#!/usr/bin/env bash
# Installs Pixar's USD reader (usd-core from PyPI) into a virtual environment
# in the build tree on first use, then checks an exported frame with it.
#   run_check.sh <venv dir> <file.usda>
set -euo pipefail
venv="$1"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import pxr" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet "usd-core==24.11"
fi
exec "$venv/bin/python" "$(dirname "$0")/check_usd.py" "$2"
