#!/usr/bin/env bash
# Make .venv (Python 3.11, or python3 if it is >= 3.11) with pursuit-bench (editable) and the extras
# named, comma-separated (pyproject.toml): install.sh [EXTRAS], by default `train` (the command line,
# training, evaluation, recordings: what scripts/demo.sh runs); `train,test,docs` is what
# scripts/test.sh installs; '' installs the environment alone (numpy, pymunk, Gymnasium, PettingZoo,
# numba). Idempotent: a second run only checks.
# With any extra, torch's CPU build is installed first. With the docs extra, the site's browser checks
# (tests/test_docs_site.py) need Chromium: where it is missing, this installs Debian's through apt when
# it runs as root with apt, and otherwise says that those checks will be skipped.
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1-train}"
python=python3.11
command -v "$python" >/dev/null || python=python3
"$python" -c 'import sys; sys.exit(sys.version_info < (3, 11))' || { echo "pursuit-bench needs Python >= 3.11" >&2; exit 2; }
[ -x .venv/bin/python ] || "$python" -m venv .venv
pip=(.venv/bin/python -m pip install -q --disable-pip-version-check)
# The CPU build by name (2.13.0+cpu), before the package, so that pip never pulls the CUDA build
# (several GB): from the configured sources if they hold it, else from PyTorch's CPU index.
if [ -n "$extras" ] && ! .venv/bin/python -c 'import torch, sys; sys.exit(torch.__version__ != "2.13.0+cpu")' 2>/dev/null; then
  "${pip[@]}" "torch==2.13.0+cpu" 2>/dev/null || "${pip[@]}" "torch==2.13.0+cpu" --index-url https://download.pytorch.org/whl/cpu
fi
if [ -n "$extras" ]; then "${pip[@]}" -e ".[${extras}]"; else "${pip[@]}" -e .; fi
if [[ ",${extras}," == *",docs,"* ]] && ! command -v chromium >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "installing Debian's Chromium (apt-get) for the site's browser checks (tests/test_docs_site.py)" >&2
    log=$(mktemp)
    if ! { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        chromium fonts-liberation; } >"$log" 2>&1; then
      tail -n 5 "$log" >&2
      echo "apt-get could not install Chromium (above): the site's browser checks will be skipped" >&2
    fi
    rm -f "$log"
  else
    echo "Chromium is not installed (Debian: apt-get install chromium, as root): the site's browser checks" \
      "(tests/test_docs_site.py) will be skipped" >&2
  fi
fi
