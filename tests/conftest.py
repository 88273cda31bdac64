"""Shared fixtures."""

import pytest
import torch


@pytest.fixture
def one_thread():
    """torch on one thread, as training runs by default: results repeat bit for bit."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)
