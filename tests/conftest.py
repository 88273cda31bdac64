"""Shared fixtures."""

import os
import signal
import subprocess

import pytest
import torch


@pytest.fixture
def one_thread():
    """torch on one thread, as training runs by default: results repeat bit for bit."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


@pytest.fixture
def processes():
    """``start(command)`` starts a process in a session of its own (stdout and stderr piped,
    text); whatever happens in the test, every one still running at its end is killed with its
    children (a sweep's workers), so that no test leaves a process behind."""
    started: list[subprocess.Popen] = []

    def start(command: list[str]) -> subprocess.Popen:
        process = subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
        )
        started.append(process)
        return process

    yield start
    for process in started:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
