#!/usr/bin/env bash
# The speed benchmarks, side by side with the peers (MPE2, VMAS, JaxMARL) in one process each.
# They get their own environment, .venv-bench: JaxMARL pins an older gymnasium than ours.
set -euo pipefail
cd "$(dirname "$0")/.."
python=python3.11; command -v "$python" >/dev/null || python=python3
"$python" -c 'import sys; sys.exit(sys.version_info < (3, 11))' || { echo "needs Python >= 3.11" >&2; exit 2; }
[ -x .venv-bench/bin/python ] || "$python" -m venv .venv-bench
pip=(.venv-bench/bin/python -m pip install -q --disable-pip-version-check)
"${pip[@]}" "torch==2.13.0+cpu" 2>/dev/null || "${pip[@]}" "torch==2.13.0+cpu" --index-url https://download.pytorch.org/whl/cpu
"${pip[@]}" -e ".[bench]"
.venv-bench/bin/python benchmarks/bench_env.py "$@"
.venv-bench/bin/python benchmarks/bench_train.py
.venv-bench/bin/python benchmarks/bench_recording.py
.venv/bin/python benchmarks/bench_perturb.py
.venv/bin/python benchmarks/bench_mkl.py
