"""The Gait-Net data set: protocol, rows, folder format, resumption, check, parallel runs."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from gaitnet_mpc.cli import main
from gaitnet_mpc.dataset import FEATURE_NAMES, CollectProtocol, DatasetError
from gaitnet_mpc.dataset.check import check_dataset
from gaitnet_mpc.dataset.store import MANIFEST, folder_lock
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.experiments.collect import CollectOptions, collect

KD_BIPED = ["--robot", "biped2d", "--teacher", "kd", "--no-progress"]


def _collect(folder: Path, *extra: str) -> int:
    return main(["collect", "--out", str(folder), *KD_BIPED, *extra])


def test_protocol_sets_depend_on_seed_and_index_only():
    a = CollectProtocol(sets=15, seed=3).set_specs()
    b = CollectProtocol(sets=15, seed=3).set_specs()
    assert a == b
    assert CollectProtocol(sets=15, seed=4).set_spec(2) != a[2]
    speeds = [s.vx_mps for s in a]
    assert all(0.0 <= v <= 1.0 for v in speeds) and len(set(speeds)) == 15
    assert a[0].seconds == pytest.approx(40.0) and a[0].push_start_s == pytest.approx(20.0)
    # sets of a longer protocol keep their speeds and seeds: only the time split changes
    assert CollectProtocol(sets=15, seed=3, seconds_total=30).set_spec(4).vx_mps == a[4].vx_mps


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"teacher": "mpc"}, "--teacher"),
        ({"robot": "quadruped"}, "--robot"),
        ({"sets": 0}, "--sets"),
        ({"sets": 10, "seconds_total": 5.0}, "--seconds"),
        ({"duration_range_s": (0.4, 0.15)}, "duration_range_s"),
    ],
)
def test_protocol_rejects_bad_settings(kwargs, field):
    with pytest.raises(ConfigError) as err:
        CollectProtocol(**kwargs)
    assert err.value.field == field


def test_collect_options_reject_bad_settings():
    with pytest.raises(ConfigError, match="--workers"):
        CollectOptions(workers=0)
    with pytest.raises(ConfigError, match="--address"):
        CollectOptions(address="10.0.0.1:6379")


@pytest.mark.slow
def test_collect_resumes_redoes_only_deleted_sets_and_is_reproducible(tmp_path, capsys):
    folder = tmp_path / "D"
    assert _collect(folder, "--sets", "2", "--seconds", "10", "--workers", "2") == 0
    files = sorted(p.name for p in folder.glob("*.parquet"))
    assert files == ["set_000.parquet", "set_001.parquet"]
    manifest = json.loads((folder / MANIFEST).read_text())
    assert manifest["complete"] and manifest["totals"]["sets"] == 2
    assert manifest["features"] == list(FEATURE_NAMES) and manifest["label"] == "dt_s"
    assert "--teacher kd" in manifest["command"]
    sha = {e["file"]: e["sha256"] for e in manifest["sets"]}
    assert check_dataset(folder)["files"] == 2
    capsys.readouterr()

    assert _collect(folder, "--sets", "2", "--seconds", "10", "--workers", "2") == 0
    assert "nothing to do" in capsys.readouterr().out

    (folder / "set_000.parquet").unlink()
    assert _collect(folder, "--sets", "2", "--seconds", "10", "--workers", "1") == 0
    out = capsys.readouterr().out
    assert "collecting 1 of 2 sets (1 already in" in out and "set_000" in out
    again = json.loads((folder / MANIFEST).read_text())
    # bit for bit: the redone set (1 worker) equals the first one (2 workers)
    assert {e["file"]: e["sha256"] for e in again["sets"]} == sha

    # the rows are physical: steps of the drawn durations, feet on either side
    import pyarrow.parquet as pq

    table = pq.read_table(folder / "set_001.parquet").to_pydict()
    col = {k: np.asarray(v) for k, v in table.items()}
    assert len(col["dt_s"]) >= 10
    assert np.all((col["dt_s"] >= 0.03 - 1e-9) & (col["dt_s"] <= 0.08 + 1e-9))
    assert len(np.unique(col["dt_s"])) > 3
    # each step lasted its drawn duration, h' = 5 stages of dt (1 ms ticks)
    ratio = col["step_duration_s"] / (5 * col["dt_s"])
    assert np.median(ratio) == pytest.approx(1.0, abs=0.02)
    assert set(col["stance_foot"]) == {"left", "right"}
    assert np.all(col["com_z_m"] > 0.2)
    assert col["push_phase"].any() and not col["push_phase"].all()


@pytest.mark.slow
def test_check_names_file_and_field_of_a_corrupted_copy(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    folder = tmp_path / "D"
    assert _collect(folder, "--sets", "1", "--seconds", "3", "--workers", "1") == 0
    assert main(["dataset", "check", str(folder)]) == 0

    data = (folder / "set_000.parquet").read_bytes()
    broken = bytearray(data)
    broken[len(broken) // 2] ^= 0xFF
    (folder / "set_000.parquet").write_bytes(bytes(broken))
    with pytest.raises(DatasetError) as err:
        check_dataset(folder)
    assert (err.value.file, err.value.field) == ("set_000.parquet", "sha256")
    assert main(["dataset", "check", str(folder)]) == 2

    # a NaN written with a matching checksum is caught by its column
    (folder / "set_000.parquet").write_bytes(data)
    table = pq.read_table(folder / "set_000.parquet")
    values = table.column("com_vx_mps").to_numpy().copy()
    values[1] = np.nan
    i = table.column_names.index("com_vx_mps")
    table = table.set_column(i, table.schema.field(i), pa.array(values))
    pq.write_table(table, folder / "set_000.parquet")
    from gaitnet_mpc.dataset.store import sha256_file

    manifest = json.loads((folder / MANIFEST).read_text())
    manifest["sets"][0]["sha256"] = sha256_file(folder / "set_000.parquet")
    (folder / MANIFEST).write_text(json.dumps(manifest))
    with pytest.raises(DatasetError) as err:
        check_dataset(folder)
    assert (err.value.file, err.value.field) == ("set_000.parquet", "com_vx_mps")


def test_check_without_manifest_and_other_protocol_refused(tmp_path):
    with pytest.raises(DatasetError, match=r"manifest\.json"):
        check_dataset(tmp_path)
    (tmp_path / MANIFEST).write_text(json.dumps({"schema_version": 1, "protocol": {}}))
    with pytest.raises(DatasetError, match="columns"):
        check_dataset(tmp_path)


def test_second_collect_into_a_locked_folder_stops_at_once(tmp_path):
    protocol = CollectProtocol(robot="biped2d", teacher="kd", sets=1, seconds_total=2.0)
    with folder_lock(tmp_path), pytest.raises(ConfigError, match="no other collect"):
        collect(protocol, tmp_path, CollectOptions(progress=False), log=lambda _: None)


def test_collect_refuses_a_folder_of_another_protocol(tmp_path):
    folder = tmp_path / "D"
    protocol = CollectProtocol(robot="biped2d", teacher="kd", sets=1, seconds_total=2.0)
    folder.mkdir()
    (folder / MANIFEST).write_text(
        json.dumps({"protocol_fingerprint": "0", "protocol": {"sets": 2}})
    )
    with pytest.raises(ConfigError, match=r"sets 2 -> 1"):
        collect(protocol, folder, CollectOptions(progress=False), log=lambda _: None)


@pytest.mark.slow
def test_sigterm_keeps_finished_sets(tmp_path):
    folder = tmp_path / "D"
    cmd = [sys.executable, "-m", "gaitnet_mpc.cli", "collect", "--out", str(folder)]
    cmd += [*KD_BIPED, "--sets", "2", "--seconds", "4", "--workers", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, env=os.environ.copy())
    assert proc.stdout is not None
    deadline = time.monotonic() + 300
    for line in proc.stdout:
        if line.startswith("[1/2]") or time.monotonic() > deadline:
            break
    proc.send_signal(signal.SIGTERM)
    rest = proc.communicate(timeout=60)[0]
    assert proc.returncode == 130, rest
    assert "interrupted: 1 of 2 sets" in rest
    manifest = json.loads((folder / MANIFEST).read_text())
    assert not manifest["complete"] and len(manifest["sets"]) == 1
    assert not list(folder.glob(".*.part"))
    check_dataset(folder)


@pytest.mark.slow
def test_ray_backend_writes_the_same_folder_format(tmp_path):
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        protocol = CollectProtocol(robot="biped2d", teacher="kd", sets=2, seconds_total=4.0)
        ray_dir, local_dir = tmp_path / "ray", tmp_path / "local"
        collect(protocol, ray_dir, CollectOptions(backend="ray", progress=False), log=print)
    finally:
        ray.shutdown()
    collect(protocol, local_dir, CollectOptions(workers=1, progress=False), log=print)
    assert check_dataset(ray_dir) == check_dataset(local_dir)
    for name in ("set_000.parquet", "set_001.parquet"):
        assert (ray_dir / name).read_bytes() == (local_dir / name).read_bytes()


@pytest.mark.slow
def test_wbmpc_teacher_gives_rows(tmp_path):
    protocol = CollectProtocol(robot="biped2d", teacher="wbmpc", sets=1, seconds_total=2.5)
    manifest = collect(protocol, tmp_path, CollectOptions(progress=False), log=print)
    assert manifest["totals"]["rows"] >= 3
    check_dataset(tmp_path)
