#!/usr/bin/env bash
# Make .venv (Python >= 3.11) with the CPU build of torch and pursuit-bench (editable) in it.
# Idempotent: a second run only checks. Extras to install can be passed: install.sh test,mpe2
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-test}"
python3 -c 'import sys; sys.exit(sys.version_info < (3, 11))' || { echo "pursuit-bench needs Python >= 3.11" >&2; exit 2; }
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --disable-pip-version-check "torch==2.13.0"  # CPU build, before the package
.venv/bin/python -m pip install -q --disable-pip-version-check -e ".[${extras}]"
