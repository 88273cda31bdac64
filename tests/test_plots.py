"""What the figures say about themselves (issue 67): the block a learning curve's points are means
of, predators' lines that stay visible when their returns coincide, and what modes.png's band is."""

import matplotlib
import numpy as np

from pursuit_bench.figures import plots

matplotlib.use("Agg")


def _curve(ends: list[int]) -> dict:
    starts = [0, *ends[:-1]]
    return {"episodes": [(s + e) / 2 for s, e in zip(starts, ends, strict=True)], "seeds": 1, "series": {}}


def test_the_curves_title_names_the_block_its_points_are_means_of() -> None:
    assert plots._block_words({"1p-high": {"hierarchical": _curve([150, 300, 450, 600])}}) == (
        "block means of 150 episodes"
    )
    assert plots._block_words({"1p-high": {"hierarchical": _curve([1, 2, 3])}}) == "one point per episode"
    uneven = {"1p-high": {"hierarchical": _curve([100, 200, 300]), "flat": _curve([50, 100, 150])}}
    assert plots._block_words(uneven) == "block means of up to 100 episodes"


def test_a_later_predator_s_line_is_narrower_and_marked_so_that_neither_hides_the_other() -> None:
    first, second, third = (plots._marks(f"predator_{k}", 100) for k in range(3))
    assert "marker" not in first and second["marker"] != third["marker"]
    assert first["lw"] > second["lw"] > third["lw"]
    assert second["markevery"] != third["markevery"]  # the markers at points of their own
    assert "marker" not in plots._marks("prey_0", 100)


def _titles(png_maker) -> list[str]:
    """The axes' titles of the figure a plotting function draws (its savefig intercepted)."""
    seen: list[str] = []
    original = plots._png

    def keep(fig):
        seen.extend(ax.get_title() for ax in fig.axes)
        return original(fig)

    plots._png = keep
    try:
        png_maker()
    finally:
        plots._png = original
    return seen


def test_modes_png_says_what_its_band_is() -> None:
    bins = np.linspace(0, 1, 6).tolist()
    one_run = {"predator_0": {"bins": bins, "p_chase": [0.9, 0.5, 0.2, None, 0.0], "states": [10, 8, 5, 0, 2]}}
    seeds = {"2 predators": {**one_run["predator_0"], "ci": [[0.8, 0.4, 0.1, None, 0.0], [1.0, 0.6, 0.3, None, 0.1]]}}
    assert "Wilson's 95 % interval" in _titles(lambda: plots.modes_png(one_run, "t"))[0]
    assert "95 % t-interval over seeds" in _titles(lambda: plots.modes_png(seeds, "t"))[0]


def test_an_outside_agent_s_bar_is_labelled_by_its_spec_s_last_part() -> None:
    assert plots._bar_label("external (/tmp/x/runs/ppo_predator.zip)") == "external\nppo_predator.zip"
    assert plots._bar_label("external (my_agents:make)") == "external\nmy_agents:make"
    assert plots._bar_label("hierarchical") == "hierarchical"
