#!/usr/bin/env bash
# The main job: install, then a short training run and its evaluation, end to end.
# Results land in runs/demo/: metrics.jsonl, checkpoint.pt, eval.json, eval.png, train.rrd, eval.rrd.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh test
.venv/bin/pursuit-bench train --condition 1p-high --episodes 1000 --out runs/demo --force
.venv/bin/pursuit-bench eval runs/demo --episodes 1000
echo "open the recordings with: .venv/bin/pursuit-bench view runs/demo"
