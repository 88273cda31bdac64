#!/usr/bin/env bash
# The test suite as CI runs it: install, lint, type-check, then pytest on both cores.
set -euo pipefail
cd "$(dirname "$0")/.."
# train,test,docs: the training stack, the test tools, the site's tools; and Chromium for the site's browser
# checks where it can be installed (install.sh says what it did; without it those checks are skipped, saying why)
bash scripts/install.sh train,test,docs
.venv/bin/ruff check .
.venv/bin/ruff format --check .
.venv/bin/mypy
# the tests marked `long` (minutes each) are left out: CI's suite stays under 8 minutes on 2 cores;
# `.venv/bin/python -m pytest -n 2 -q -m long` runs them (docs/getting-started.md, "The tests")
.venv/bin/python -m pytest -n 2 -q -m "not long"
