"""The budget study's rates and its first equality check (PLAN.md, "What it costs").

For each of the study's conditions, one population member of each kind (hierarchical seed 1000,
flat seed 1004) is trained to 15,000 episodes by the rule study's own plan (a sweep of one run:
a run alone equals the same run in a stack), its prey's weights compared with the committed
rule-study population's to the bit, then trained on from its 15,000-episode checkpoint for
``--more`` episodes in this process, whose CPU time (``time.process_time``) is the late rate.
Run against the study's pinned build:

    PYTHONPATH=/work/budget-build nice -n 19 /work/main/.venv/bin/python studies/budget/measure.py \\
        --work /work/budget-study/measure --out studies/budget/rates.json
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import sys
import time
from pathlib import Path
from typing import Any


def _own_design() -> Any:
    """The study's design beside this file, as a module of its own name (the residual study's
    driver has a ``design`` of its own: a test process may load both)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("budget_design", Path(__file__).resolve().parent / "design.py")
    assert spec is not None and spec.loader is not None
    module = sys.modules.setdefault("budget_design", importlib.util.module_from_spec(spec))
    if not hasattr(module, "CONDITIONS"):
        spec.loader.exec_module(module)
    return module


design = _own_design()
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "common"))  # the drivers' shared module alone
import driver  # noqa: E402

child_cpu = driver.child_cpu


def measure(work: Path, condition: str, kind: str, seed: int, more: int) -> dict[str, Any]:
    from pursuit_bench.training import runs
    from pursuit_bench.training.stack import FolderRun, train_stack
    from pursuit_bench.training.sweep import open_sweep, run_sweep

    plan = design.sweep_plan(kind, [condition], seed, 1, design.RULE_EPISODES, ())
    folder = work / f"{condition}-{kind}-seed{seed}"
    open_sweep(folder, plan)
    before = child_cpu()
    start = time.monotonic()
    run_sweep(folder, plan, workers=1, record=False)
    first_cpu, first_wall = child_cpu() - before, time.monotonic() - start
    name = f"{condition}-{kind}-seed{seed}"
    run = folder / "runs" / name
    equal, differs = design.prey_equals_committed(run, runs.CHECKPOINT, condition, f"{kind}-seed{seed}")
    late = work / "late" / name
    if late.exists():
        shutil.rmtree(late)
    late.mkdir(parents=True)
    for file in (runs.CONFIG, runs.CHECKPOINT, runs.METRICS):
        shutil.copy2(run / file, late / file)
    config, settings = runs.read_config(late)
    state = runs.load_checkpoint(late)
    done = int(state["episodes_done"])
    extended = config.__class__.from_dict({**config.to_dict(), "episodes": done + more})
    runs.write_config(late, extended, settings)
    cpu = time.process_time()
    start = time.monotonic()
    with runs.locked(late):
        train_stack([FolderRun(late, extended, settings, state)], record=False)
    late_cpu, late_wall = time.process_time() - cpu, time.monotonic() - start
    rows = [json.loads(line) for line in (late / runs.METRICS).read_text().splitlines()]
    late_rows = [r for r in rows if r["episode"] > done]
    last_rule = [r for r in rows if r["episode"] <= done][-1]
    return {
        "condition": condition,
        "kind": kind,
        "seed": seed,
        "first_15000": {"cpu_s": round(first_cpu, 1), "wall_s": round(first_wall, 1)},
        "prey_equal_to_committed": equal,
        "differing_tensors": differs,
        "schedules_at_15000": {k: last_rule.get(k) for k in ("epsilon", "beta")},
        "late": {
            "episodes": len(late_rows),
            "cpu_s": round(late_cpu, 2),
            "wall_s": round(late_wall, 2),
            "cpu_s_per_1000_episodes": round(1000 * late_cpu / max(len(late_rows), 1), 2),
            "mean_length": round(statistics.fmean(r["length"] for r in late_rows), 1),
        },
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--work", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--more", type=int, default=2000, help="Episodes trained past 15,000 and timed.")
    parser.add_argument("--conditions", default=",".join(design.CONDITIONS))
    args = parser.parse_args()
    import torch

    torch.set_num_threads(1)
    chosen = args.conditions.split(",")
    if unknown := [c for c in chosen if c not in design.CONDITIONS]:
        print(f"--conditions: unknown {unknown}; expected some of {', '.join(design.CONDITIONS)}", file=sys.stderr)
        return 2
    args.work.mkdir(parents=True, exist_ok=True)
    rows = json.loads(args.out.read_text())["runs"] if args.out.exists() else []
    for condition in chosen:
        for kind in design.KINDS:
            seed = design.population_seeds(kind)[0]
            if any(r["condition"] == condition and r["kind"] == kind for r in rows):
                continue
            row = measure(args.work, condition, kind, seed, args.more)
            print(json.dumps(row), flush=True)
            rows.append(row)
            about = {
                "command": "PYTHONPATH=/work/budget-build python studies/budget/measure.py " + " ".join(sys.argv[1:]),
                "when": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                "runs": rows,
            }
            args.out.write_text(json.dumps(about, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
