"""A Ray address that does not answer is a named error within seconds (not minutes of
Ray's connection retries), and a long job stopped by SIGTERM leaves a status.json that
does not say ``running`` (issue 51)."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gaitnet_mpc.cli.main import EXIT_BAD_INPUT, main
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.parallel import check_ray_address

ENV = {**os.environ, "MUJOCO_GL": "egl", "PYTHONPATH": str(Path(__file__).parents[1] / "src")}
FAST_S = 30.0  # an unreachable address must be refused well within this [s]


def _closed_port() -> int:
    """A local port nothing listens on (bound, read, released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.mark.parametrize("address", ["nowhere:1", "CLOSED", "no-port", "host:notaport"])
def test_an_address_that_does_not_answer_is_a_named_error(address: str) -> None:
    address = address.replace("CLOSED", f"127.0.0.1:{_closed_port()}")
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match="--address") as info:
        check_ray_address(address)
    assert time.perf_counter() - t0 < FAST_S
    assert address in str(info.value) and "host:port" in str(info.value)


def test_auto_and_a_listening_port_pass() -> None:
    check_ray_address("auto")
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        check_ray_address(f"127.0.0.1:{server.getsockname()[1]}")
        check_ray_address(f"ray://127.0.0.1:{server.getsockname()[1]}")


@pytest.mark.parametrize("address", ["nowhere:1", "CLOSED"])
def test_sweep_with_an_unreachable_ray_address_exits_2_at_once(
    tmp_path: Path, capsys: pytest.CaptureFixture, address: str
) -> None:
    address = address.replace("CLOSED", f"127.0.0.1:{_closed_port()}")
    out = tmp_path / "sweep"
    t0 = time.perf_counter()
    args = ["sweep", "push", "--backend", "ray", "--address", address, "--quick"]
    code = main([*args, "--no-progress", "--out", str(out)])
    assert time.perf_counter() - t0 < FAST_S
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT, err
    assert f"--address: got {address!r}" in err and "Traceback" not in err
    status = out / "status.json"
    assert not status.exists() or json.loads(status.read_text())["state"] != "running"


def test_sigterm_during_a_sweep_leaves_a_status_that_is_not_running(tmp_path: Path) -> None:
    out = tmp_path / "sweep"
    cmd = [sys.executable, "-m", "gaitnet_mpc.cli", "sweep", "push", "--quick", "--workers"]
    cmd += ["1", "--no-progress", "--out", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV)
    try:
        deadline = time.monotonic() + 120.0
        status = out / "status.json"
        while not status.exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        if proc.poll() is not None or not status.exists():
            pytest.skip("the sweep ended (or never started) before the signal could be sent")
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    state = json.loads(status.read_text())
    if proc.returncode == 0:
        pytest.skip("the sweep finished before the signal arrived")
    assert proc.returncode == 130, err
    assert state["state"] == "interrupted" and state["exit_code"] == 130
