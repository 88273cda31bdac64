"""Statistics as the reports' tables print them: an interval, a p-value."""

from __future__ import annotations


def span_text(ci: list[float] | None, digits: int = 3) -> str:
    """An interval as the tables print it: ` [low, high]` signed, or nothing without one."""
    return f" [{ci[0]:+.{digits}f}, {ci[1]:+.{digits}f}]" if ci else ""


def p_text(value: float | None) -> str:
    """A p-value as the tables print it: three decimals, or one significant digit below 0.001."""
    if value is None:
        return "–"
    return f"{value:.3f}" if value >= 0.001 else f"{value:.0e}"
