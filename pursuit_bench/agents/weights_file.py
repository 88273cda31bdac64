"""A safetensors file of weights with a text header (a shipped agent, a team file), read with its
format checked: loading one runs no code."""

from __future__ import annotations

from pathlib import Path

import torch
from safetensors import SafetensorError, safe_open


def read(path: Path, expected_format: str, what: str) -> tuple[dict[str, torch.Tensor], dict[str, str]]:
    """(tensors by name, header) of ``path``; ValueError in one line unless it is a readable
    safetensors file whose header's ``format`` is ``expected_format`` (``what`` names it)."""
    try:
        with safe_open(str(path), framework="pt") as file:
            header = dict(file.metadata() or {})
            tensors = {name: file.get_tensor(name) for name in file.keys()}
    except (SafetensorError, OSError) as error:
        raise ValueError(f"{path}: not a readable safetensors file ({error})") from None
    if header.get("format") != expected_format:
        raise ValueError(f"{path}: not a {what} (format {expected_format!r} expected)")
    return tensors, header
