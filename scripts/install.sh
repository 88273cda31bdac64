#!/usr/bin/env bash
# Make .venv (Python 3.11, or python3 if it is >= 3.11) with the CPU build of torch and
# pursuit-bench (editable) in it. Idempotent: a second run only checks.
# Extras to install can be passed: install.sh test,mpe2. With the docs extra (install.sh test,docs,
# what scripts/test.sh installs), also Debian's Chromium for the site's browser checks
# (tests/test_docs_site.py), where this runs as root with apt; elsewhere those checks are skipped.
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
if [[ ",${extras}," == *",docs,"* ]] && ! command -v chromium >/dev/null 2>&1 \
  && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      chromium fonts-liberation; } >/dev/null 2>&1 || true
fi
