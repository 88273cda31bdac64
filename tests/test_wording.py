"""What the command line prints around numbers."""

from pursuit_bench.cli.wording import counted


def test_a_count_takes_its_noun_in_the_right_number() -> None:
    assert [counted(n, "panel") for n in (0, 1, 2)] == ["0 panels", "1 panel", "2 panels"]
    assert counted(1, "ply", "plies") == "1 ply" and counted(3, "ply", "plies") == "3 plies"
