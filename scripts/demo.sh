#!/usr/bin/env bash
# The main job: install; evaluate the shipped agents of 2p-high-individual (seconds, no training);
# then a short training run of 1p-high and its evaluation, end to end.
# Results land in runs/demo-pretrained/ (eval.json, eval.png, eval.rrd) and runs/demo/
# (config.json, metrics.jsonl, checkpoint.pt, eval.json, eval.png, train.rrd, eval.rrd).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh train  # the command line and the training stack; no test tools
.venv/bin/pursuit-bench eval --pretrained 2p-high-individual --episodes 300 --out runs/demo-pretrained
.venv/bin/pursuit-bench train --condition 1p-high --episodes 1000 --out runs/demo --force
.venv/bin/pursuit-bench eval runs/demo --episodes 1000
echo "open the recordings with: .venv/bin/pursuit-bench view runs/demo-pretrained   (or runs/demo)"
