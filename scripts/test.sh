#!/usr/bin/env bash
# The test suite as CI runs it: install, lint, type-check, then pytest on both cores.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh test,docs  # docs: the site's tools and Chromium (tests/test_docs_site.py)
.venv/bin/ruff check .
.venv/bin/ruff format --check .
.venv/bin/mypy
.venv/bin/python -m pytest -n 2 -q
