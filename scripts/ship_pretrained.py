"""Copy the agents of a finished sweep into the package (``pursuit_bench/pretrained/``).

For each condition: of the evaluated hierarchical runs, the one whose predators' mean return
(eval.json, the trained predators as evaluated) is the median over seeds; its agents' weights
go into ``DEST/<condition>/<agent>.safetensors`` with a header saying how they were trained.

    python scripts/ship_pretrained.py sweeps/repro --command "pursuit-bench sweep ..."
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from pursuit_bench import pretrained
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.training import runs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("sweep", type=Path, help="A finished sweep folder.")
    parser.add_argument("--command", required=True, help="The sweep's command line, for the files' headers.")
    parser.add_argument("--dest", type=Path, default=pretrained.FOLDER, help="Where to write [the package].")
    args = parser.parse_args()
    plan = json.loads((args.sweep / "sweep.json").read_text())["plan"]
    for condition in CONDITIONS:
        scores = {}
        for folder in sorted((args.sweep / "runs").glob(f"{condition}-hierarchical-seed*")):
            evaluation = folder / "eval.json"
            if evaluation.exists():
                panels = json.loads(evaluation.read_text())["panels"]
                scores[folder] = sum(p["trained"] for p in panels) / len(panels)
        if not scores:
            print(f"{condition}: no evaluated hierarchical run, skipped")
            continue
        chosen = pretrained.median_seed(scores)
        config, _ = runs.read_config(chosen)
        state = runs.load_checkpoint(chosen)
        ranked = ", ".join(f"seed {runs.read_config(f)[0].seed}: {s:+.3f}" for f, s in sorted(scores.items()))
        provenance = {
            "sweep_command": args.command,
            "preset": str(plan["preset"]),
            "selection": f"the median of {len(scores)} seeds by the predators' mean return in eval.json ({ranked})",
            "predators_mean_return": f"{scores[chosen]:+.4f}",
            "evaluation_episodes": str(plan["eval_episodes"]),
        }
        written = pretrained.export(
            runs.load_agents(chosen, state),
            config,
            args.dest,
            trained_episodes=int(state["episodes_done"]),
            provenance=provenance,
        )
        size = sum(p.stat().st_size for p in written)
        print(f"{condition}: seed {config.seed} ({scores[chosen]:+.3f}), {len(written)} files, {size / 1024:.0f} KiB")


if __name__ == "__main__":
    main()
