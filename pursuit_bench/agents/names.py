"""The names of the agents' kinds, as the command line, checkpoints, run folders and the studies'
files spell them: light (no torch), so that the statistics and reports can name kinds without
loading a learner. The classes in ``kinds`` and ``residual`` take their ``kind`` from here."""

from __future__ import annotations

HIERARCHICAL = "hierarchical"
"""The paper's predator: a learned mode (chase or stalk) over parallel navigation's direction."""
FLAT = "flat"
"""The ablation: one learned choice among all 24 (mode, direction) pairs, no rule."""
RESIDUAL = "residual"
"""The learned mode plus a learned correction of the rule's direction."""
PREY = "prey"
"""The learning prey."""
SCRIPTED = "scripted"
"""A fixed policy wrapped as an agent (the baselines, FleeingPrey)."""
FLEEING = "FleeingPrey"
"""The scripted prey's name as populations and the studies' results spell it (the class name of
``rules.policies.FleeingPrey``, tested)."""
WITH_AND_WITHOUT_RULE = (HIERARCHICAL, FLAT)
"""The pair the rule's value is read from (the rule study, the robustness ladders): with the
rule first, so that a difference is hierarchical − flat."""
