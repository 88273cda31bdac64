"""Words the command line prints around numbers."""


def counted(n: int, noun: str, plural: str | None = None) -> str:
    """``n`` with its noun in the right number: "1 panel", "2 panels", "0 panels"."""
    return f"{n} {noun if n == 1 else plural or noun + 's'}"
