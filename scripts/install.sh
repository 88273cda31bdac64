#!/usr/bin/env bash
# Make .venv (Python 3.11, or python3 if it is >= 3.11) with the CPU build of torch and
# pursuit-bench (editable) in it. Idempotent: a second run only checks.
# Extras to install can be passed: install.sh test,mpe2
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-test}"
python=python3.11
command -v "$python" >/dev/null || python=python3
"$python" -c 'import sys; sys.exit(sys.version_info < (3, 11))' || { echo "pursuit-bench needs Python >= 3.11" >&2; exit 2; }
[ -x .venv/bin/python ] || "$python" -m venv .venv
pip=(.venv/bin/python -m pip install -q --disable-pip-version-check)
# The CPU build by name (2.13.0+cpu), before the package, so that pip never pulls the CUDA build
# (several GB): from the configured sources if they hold it, else from PyTorch's CPU index.
if ! .venv/bin/python -c 'import torch, sys; sys.exit(torch.__version__ != "2.13.0+cpu")' 2>/dev/null; then
  "${pip[@]}" "torch==2.13.0+cpu" 2>/dev/null || "${pip[@]}" "torch==2.13.0+cpu" --index-url https://download.pytorch.org/whl/cpu
fi
"${pip[@]}" -e ".[${extras}]"
