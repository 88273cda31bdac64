"""The sweep's Ray backend on a real cluster of two nodes on this machine, one of them killed
mid-sweep, and on a local Ray instance. Every Ray process runs inside a network namespace of its
own that holds only the loopback interface, so nothing leaves the machine (Ray advertises the
machine's own address otherwise); a finaliser kills whatever is left in that namespace."""

import json
import os
import secrets
import shutil
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from cli_helpers import run_cli

RAY = Path(sys.executable).with_name("ray")


def _namespace_command() -> list[str] | None:
    """``unshare -n`` as root, ``unshare -rn`` otherwise; None where neither is allowed."""
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return None
    for command in (["unshare", "-n"], ["unshare", "-rn"]):
        try:
            if subprocess.run([*command, "true"], capture_output=True, timeout=30).returncode == 0:
                return command
        except (OSError, subprocess.TimeoutExpired):
            continue
    return None


try:
    import ray  # noqa: F401

    HAVE_RAY = RAY.exists()
except ImportError:
    HAVE_RAY = False
NAMESPACE = _namespace_command()

pytestmark = [
    pytest.mark.long,  # Ray starts its cluster for each: among the suite's longest
    pytest.mark.skipif(not HAVE_RAY, reason="Ray is not installed (pip install 'pursuit-bench[ray]')"),
    pytest.mark.skipif(NAMESPACE is None, reason="no network namespace allowed here (unshare -n and -rn refused)"),
]

SMALL = ["--conditions", "1p-low", "--seeds", "2", "--episodes", "20", "--eval-episodes", "20", "--no-record"]


@pytest.fixture
def loopback(tmp_path: Path) -> Iterator[Callable[[str, int], subprocess.CompletedProcess]]:
    """``run(script, timeout)``: bash ``script`` in a new network namespace with only loopback
    up. Whatever happens, every process still in that namespace at the end is killed."""
    marker = tmp_path / "netns"

    def run(script: str, timeout: int) -> subprocess.CompletedProcess:
        body = f"set -e\nip link set lo up\nreadlink /proc/self/ns/net > {marker}\n{script}"
        assert NAMESPACE is not None
        return subprocess.run(
            [*NAMESPACE, "bash", "-c", body], capture_output=True, text=True, timeout=timeout, start_new_session=True
        )

    yield run
    if marker.exists():
        namespace = marker.read_text().strip()
        for proc in Path("/proc").iterdir():
            if not proc.name.isdigit():
                continue
            try:
                if os.readlink(proc / "ns" / "net") == namespace:
                    os.kill(int(proc.name), signal.SIGKILL)
            except OSError:
                continue


def same_runs(a: Path, b: Path, names: list[str]) -> None:
    for name in names:
        for file in ("eval.json", "metrics.jsonl", "config.json"):
            left, right = (p / "runs" / name / file for p in (a, b))
            left_text, right_text = left.read_text(), right.read_text()
            if file == "config.json":  # the recording ids differ
                left_text, right_text = (json.loads(t)["train"] for t in (left_text, right_text))
            assert left_text == right_text, (name, file)


@pytest.mark.slow
def test_the_ray_backend_gives_the_local_backends_results(tmp_path: Path, loopback) -> None:
    sweep = [sys.executable, "-m", "pursuit_bench.cli.main", "sweep", *SMALL, "--workers", "2"]
    done = loopback(f"{' '.join(sweep)} --backend ray --out {tmp_path / 'ray'}", 600)
    assert done.returncode == 0 and "2 of 2 runs" in done.stdout + done.stderr, done.stderr[-2000:]
    code, output = run_cli("sweep", *SMALL, "--workers", "2", "--out", str(tmp_path / "local"))
    assert code == 0, output
    same_runs(tmp_path / "ray", tmp_path / "local", [f"1p-low-hierarchical-seed{s}" for s in (0, 1)])


@pytest.mark.slow
def test_a_sweep_on_two_nodes_survives_losing_one(tmp_path: Path, loopback) -> None:
    """A head and a second node (each its own raylet, one CPU each) share a token; the sweep's
    two stacks run one on each; the second node is killed while its task runs; the task is
    retried on the head and every run equals the local sweep's."""
    token = secrets.token_hex(16)
    python = sys.executable
    sweep = f"{python} -m pursuit_bench.cli.main sweep {' '.join(SMALL)} --workers 2 --backend ray"
    script = f"""
export RAY_AUTH_MODE=token RAY_AUTH_TOKEN={token}
RAYTMP=$(mktemp -d /tmp/rayXXXXXX)  # short: Ray's socket paths must stay under 108 bytes
trap 'rm -rf "$RAYTMP"' EXIT
{RAY} start --head --port=6391 --num-cpus=1 --temp-dir="$RAYTMP" --disable-usage-stats \\
    --include-dashboard=false > {tmp_path / "head.log"} 2>&1
setsid {RAY} start --address=127.0.0.1:6391 --num-cpus=1 --disable-usage-stats --block > {tmp_path / "node.log"} 2>&1 &
NODE=$!
{python} - <<'PY'
import json, time, ray
ray.init(address="127.0.0.1:6391", logging_level="ERROR")
while sum(n["Alive"] for n in ray.nodes()) < 2:
    time.sleep(0.2)
json.dump([n["NodeManagerAddress"] for n in ray.nodes() if n["Alive"]], open("{tmp_path / "nodes.json"}", "w"))
PY
{sweep} --address 127.0.0.1:6391 --out {tmp_path / "cluster"} > {tmp_path / "sweep.log"} 2>&1 &
SWEEP=$!
until ps -o args= -g $NODE | grep -q "ray::stack_task"; do sleep 0.1; done
kill -9 -- -$NODE
echo "second node killed while running a stack"
wait $SWEEP
"""
    done = loopback(script, 600)
    log = (tmp_path / "sweep.log").read_text() if (tmp_path / "sweep.log").exists() else ""
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:] + log[-2000:]
    assert "second node killed while running a stack" in done.stdout
    assert "2 of 2 runs" in log, log[-2000:]
    nodes = json.loads((tmp_path / "nodes.json").read_text())
    assert nodes == ["127.0.0.1", "127.0.0.1"]  # both nodes on loopback: nothing leaves the machine
    code, output = run_cli("sweep", *SMALL, "--workers", "2", "--out", str(tmp_path / "local"))
    assert code == 0, output
    same_runs(tmp_path / "cluster", tmp_path / "local", [f"1p-low-hierarchical-seed{s}" for s in (0, 1)])
