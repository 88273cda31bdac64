#!/usr/bin/env bash
# The main job: install, then a short scripted demo of the ten conditions.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh test
.venv/bin/python -m pursuit_bench.demo
