"""The paper's 3-D figures (``experiments/paper_figures.py``) and ``reproduce all``
(``experiments/reproduce_all.py``): one quick ``reproduce all`` runs every table and
figure; each quick figure wrote its files (PNG, SVG, CSV, Markdown with a verdict and the
machine line), the physical facts of the quick runs that are robust hold (touchdowns on
allowed patches, predictions that move with the measured momentum, a tracked command,
swinging feet, a cart pushed forward by the hands), and ``reproduction.md`` has a section
for every table and figure of the paper."""

from __future__ import annotations

import csv
import os
import re
import time
import tomllib

os.environ.setdefault("MUJOCO_GL", "egl")

from pathlib import Path

import numpy as np
import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.experiments.figure_fig10 import CART_LOAD_KG
from gaitnet_mpc.experiments.paper_figures import (
    ARTIFACTS,
    CSV_FIELDS,
    FIGURES,
    QUICK_DURATION_S,
    VX_MPS,
    reproduce_figure,
)
from gaitnet_mpc.experiments.reproduce_all import ITEMS, SECTIONS, reproduce_all
from gaitnet_mpc.machine import machine_info
from gaitnet_mpc.results.rundir import CONFIG, load_run
from gaitnet_mpc.terrain import load_course

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def everything(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``reproduce all --quick`` into a fresh folder (its wall time is printed)."""
    out = tmp_path_factory.mktemp("all")
    lines: list[str] = []
    t0 = time.perf_counter()
    md = reproduce_all(out, quick=True, video=False, log=lines.append)
    print(f"reproduce all --quick: {time.perf_counter() - t0:.0f} s")
    assert md == out / "reproduction.md"
    assert [line.split(":")[0] for line in lines if line.endswith("...")] == list(ITEMS)
    return out


@pytest.fixture(scope="module")
def fig7(everything: Path) -> Path:
    return everything / "fig7"


@pytest.fixture(scope="module")
def fig8(everything: Path) -> Path:
    return everything / "fig8"


@pytest.fixture(scope="module")
def fig10(everything: Path) -> Path:
    return everything / "fig10"


@pytest.fixture(scope="module")
def fig11(everything: Path) -> Path:
    return everything / "fig11"


@pytest.fixture(scope="module")
def obstacle(everything: Path) -> Path:
    return everything / "obstacle"


def _rows(out: Path, name: str) -> list[dict[str, str]]:
    with (out / f"{name}.csv").open() as fh:
        reader = csv.DictReader(fh)
        assert reader.fieldnames == CSV_FIELDS[name].split()
        return list(reader)


def _floats(rows: list[dict[str, str]], key: str) -> np.ndarray:
    return np.array([float(r[key]) for r in rows])


def _check_files(out: Path, name: str) -> str:
    """Every file of the figure is there and sensible; returns the Markdown text."""
    from PIL import Image

    for item in ARTIFACTS[name]:
        path = out / item
        if item in ("fig10_loads.jsonl", "courses"):  # load search, seeded layouts: not quick
            assert not path.exists()
            continue
        assert path.exists(), item
        if path.is_file():
            assert path.stat().st_size > 0, item
    with Image.open(out / f"{name}.png") as img:
        width, height = img.size
    assert width >= 800 and height >= 400
    assert (out / f"{name}.svg").read_text().lstrip().startswith(("<?xml", "<svg"))
    text = (out / f"{name}.md").read_text()
    assert "holds" in text or "does not hold" in text
    assert machine_info(("numpy", "mujoco", "pin")) in text
    assert "wall time:" in text
    for run_dir in (out / "runs").iterdir():  # full run folders, read back
        run = load_run(run_dir)
        assert run.summary["duration_s"] <= QUICK_DURATION_S[name] + 1e-6
        assert not (run_dir / "video.mp4").exists()  # quick: no video
    return text


#: A settings file of an option (the reach rows), for fig9's ``--config``.
_REACH = Path(__file__).resolve().parents[1] / "benchmarks" / "configs" / "leg_reach.toml"


# ----------------------------------------------------------------------------- names
def test_figures_are_named_for_help() -> None:
    assert set(FIGURES) == {"fig7", "fig8", "fig9", "fig10", "fig11", "obstacle"}
    assert all(isinstance(line, str) and line for line in FIGURES.values())


def test_a_bad_name_is_refused_before_any_work(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="figure") as info:
        reproduce_figure("fig99", tmp_path / "x", quick=True, video=False)
    assert info.value.field == "figure"
    assert not (tmp_path / "x").exists()


# ----------------------------------------------------------------------------- fig7
def test_fig7_files_and_touchdowns_on_allowed_patches(fig7: Path) -> None:
    text = _check_files(fig7, "fig7")
    rows = _rows(fig7, "fig7")
    kinds = {r["kind"] for r in rows}
    assert kinds == {"touchdown", "patch", "com_region"}
    course = load_course("stepping-stones")
    assert sum(r["kind"] == "patch" for r in rows) == len(course.patches)
    assert sum(r["kind"] == "com_region" for r in rows) == len(course.patches) - 2  # stones
    for r in (r for r in rows if r["kind"] == "com_region"):
        stone = course.patches[int(r["index"])]
        # the region holds its stone (reach >= 0): a CoM above the stone makes it a candidate
        assert float(r["x_min_m"]) < stone.x_center_m < float(r["x_max_m"])
        assert float(r["y_min_m"]) < stone.y_center_m < float(r["y_max_m"])
    touchdowns = [r for r in rows if r["kind"] == "touchdown"]
    assert len(touchdowns) >= 5  # 2.5 s of walking, a step every ~0.25 s
    run = load_run(fig7 / "runs" / "gaitnet-stones")
    if not run.summary["fell"]:
        for r in touchdowns:
            x, y = float(r["x_m"]), float(r["y_m"])
            assert course.foot_allowed(x, y, r["foot"]), r
            assert r["allowed"] == "1"
        assert "**holds**" in text  # no fall, no violation: the quick rule holds
    assert (fig7 / "fig7_strip.png").stat().st_size > 10_000


# ----------------------------------------------------------------------------- fig8
def test_fig8_predictions_move_with_the_measured_momentum(fig8: Path) -> None:
    text = _check_files(fig8, "fig8")
    rows = _rows(fig8, "fig8")
    assert {r["controller"] for r in rows} == {"gaitnet", "kd"}
    for controller in ("gaitnet", "kd"):
        mine = [r for r in rows if r["controller"] == controller]
        assert len(mine) >= 5  # a step start every ~0.25 s
        for key in CSV_FIELDS["fig8"].split()[1:]:
            assert np.isfinite(_floats(mine, key)).all(), (controller, key)
        t, t_pred = _floats(mine, "t_s"), _floats(mine, "t_pred_s")
        assert np.all(np.diff(t) > 0) and np.all(t_pred > t)  # one stage ahead
        assert np.all(t_pred - t < 0.1)  # a stage is one MPC dt (at most 0.07 s)
        pred, meas = _floats(mine, "lGx_pred"), _floats(mine, "lGx_meas")
        assert np.corrcoef(pred, meas)[0, 1] > 0.5  # the forward momentum ramps up
    assert "RMSE / std" in text


# ----------------------------------------------------------------------------- fig11
def test_fig11_tracks_the_command_over_the_gap(fig11: Path) -> None:
    _check_files(fig11, "fig11")
    rows = _rows(fig11, "fig11")
    g0, g1 = 1.5, 1.7  # the built-in gap
    for controller in ("gaitnet", "kd"):
        mine = [r for r in rows if r["controller"] == controller]
        assert len(mine) >= 100
        t, x, vx = (_floats(mine, k) for k in ("t_s", "com_x_m", "com_vx_mps"))
        assert np.allclose(_floats(mine, "cmd_vx_mps"), VX_MPS)
        ramp = _floats(mine, "ramped_cmd_vx_mps")
        assert ramp[0] == 0.0 and np.all(np.diff(ramp) >= 0) and ramp[-1] == VX_MPS
        over = np.array([r["com_over_gap"] == "1" for r in mine])
        assert np.array_equal(over, (x >= g0) & (x <= g1))
        run = load_run(fig11 / "runs" / f"{controller}-gap")
        if not run.summary["fell"]:
            assert over.any()  # 3 s at 0.75 m/s reach the gap
            assert abs(float(np.mean(vx[t >= 1.0])) - VX_MPS) < 0.15


# ----------------------------------------------------------------------------- obstacle
def test_obstacle_feet_swing_and_touch_down(obstacle: Path) -> None:
    text = _check_files(obstacle, "obstacle")
    rows = _rows(obstacle, "obstacle")
    trace = [r for r in rows if r["kind"] == "trace"]
    touchdowns = [r for r in rows if r["kind"] == "touchdown"]
    assert len(touchdowns) >= 5
    for foot in ("left", "right"):
        mine = [r for r in trace if r["foot"] == foot]
        assert len(mine) >= 100
        t, z = _floats(mine, "t_s"), _floats(mine, "sole_z_m")
        assert np.isfinite(z).all()
        early = t < 2.0  # flat ground before the obstacle (x = 1.45 m at 0.5 m/s)
        assert z[early].min() < 0.005  # it stands on the ground
        assert z[early].max() > 0.01  # and swings
    assert any(r["over_obstacle"] == "1" for r in trace)  # 4 s reach the obstacle
    assert "clearance" in text and " cm" in text
    assert "obstacle_heights" in text  # the deviation from the paper is stated


# ----------------------------------------------------------------------------- fig10
def test_fig10_the_hands_push_the_cart_forward(fig10: Path) -> None:
    text = _check_files(fig10, "fig10")
    rows = _rows(fig10, "fig10")
    assert {r["controller"] for r in rows} == {"srbm", "gaitnet"}
    for controller in ("srbm", "gaitnet"):
        mine = [r for r in rows if r["controller"] == controller]
        t, com_x, cart_x, push = (
            _floats(mine, k) for k in ("t_s", "com_x_m", "cart_x_m", "hand_push_n")
        )
        assert len(mine) >= 400  # 2.5 s, a row every 5 ms
        run = load_run(fig10 / "runs" / f"{controller}-cart")
        assert run.summary["cart"]["load_kg"] == CART_LOAD_KG  # recorded, not told
        assert np.all(push >= 0.0)  # a frictionless plate pushes back, never pulls
        assert push.max() > 10.0  # the hands touched it
        assert np.all(np.diff(cart_x) >= -1e-3)  # Coulomb resistance: it never rolls back
        if not run.summary["fell"]:
            assert cart_x[-1] - cart_x[0] > 0.2  # pushed forward
            assert np.all(cart_x > com_x)  # ahead of the robot, as a pushed cart is
            since = _floats(mine, "t_since_contact_s")
            assert np.allclose(since, t - (t[0] - since[0]))
        no_cart = load_run(fig10 / "runs" / f"{controller}-no-cart")
        assert no_cart.summary["cart"] is None
    assert "not searched (quick)" in text
    assert "struggles" in text and "torque headroom" in text


# ----------------------------------------------------------------------------- all
def test_reproduction_document_has_every_table_and_figure(everything: Path) -> None:
    doc = (everything / "reproduction.md").read_text()
    headings = re.findall(r"^## (.+)$", doc, flags=re.M)
    assert headings == [s.title for s in SECTIONS]
    for needed in ("Table I", "Table II", "Fig. 4", "Fig. 6", "Fig. 7", "Fig. 8", "Fig. 9",
                   "Fig. 10", "Fig. 11"):  # fmt: skip
        assert any(h.startswith(needed + ":") for h in headings), needed
    for link in re.findall(r"!\[[^]]*\]\(([^)]+)\)", doc):
        assert (everything / link).is_file(), link
    assert "fig10/fig10.png" in doc and "table1/fig4.png" in doc and "fig9/fig9.png" in doc
    fig4 = doc.split("## Fig. 4")[1].split("\n## ")[0]
    assert "drawn by Table I" in fig4
    for name in ITEMS:
        assert (everything / name / f"{name}.md").is_file(), name
    assert doc.count("holds") >= 5  # the figures' verdicts are carried over


def test_reproduce_all_resumes_without_running_again(everything: Path) -> None:
    lines: list[str] = []
    before = (everything / "fig10" / "fig10.csv").stat().st_mtime_ns
    reproduce_all(everything, quick=True, video=False, log=lines.append)
    assert all("done earlier" in line for line in lines) and len(lines) == len(ITEMS)
    assert (everything / "fig10" / "fig10.csv").stat().st_mtime_ns == before  # not re-run


# ----------------------------------------------------------------------------- fig9
def test_fig9_step_durations_within_the_bounds(everything: Path) -> None:
    out = everything / "fig9"
    text = _check_files(out, "fig9")
    rows = _rows(out, "fig9")
    assert {r["run"] for r in rows} == {"reference", "push", "payload", "uneven"}
    dt = _floats(rows, "dt_s")
    assert np.all((dt >= 0.045 - 1e-9) & (dt <= 0.07 + 1e-9))  # the paper's clip
    assert np.allclose(_floats(rows, "step_s"), 5 * dt)
    for r in rows:
        assert r["nominal"] == ("1" if abs(float(r["dt_s"]) - 0.045) <= 0.001 else "0")
    push = [r for r in rows if r["run"] == "push"]
    assert all(r["disturbed"] == ("1" if float(r["t_s"]) >= 4.0 else "0") for r in push)
    for name in ("reference", "push", "payload", "uneven"):
        t = _floats([r for r in rows if r["run"] == name], "t_s")
        assert len(t) >= 6 and np.all(np.diff(t) > 0.15)  # one per step (>= 0.225 s apart)
    run = load_run(out / "runs" / "gaitnet-payload")
    assert run.summary["payload_kg"] == 1.5
    assert "preview" in text  # the deviation from the paper's unknown terrain is stated


def test_only_fig9_takes_a_settings_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="fig9 only") as info:
        reproduce_figure("fig7", tmp_path / "x", quick=True, video=False, config_file=_REACH)
    assert info.value.field == "--config"
    assert not (tmp_path / "x").exists()


def test_fig9_runs_with_a_settings_file(tmp_path: Path) -> None:
    """``reproduce fig9 --config``: every run takes the file's settings, the report says so."""
    path = reproduce_figure("fig9", tmp_path / "fig9", quick=True, video=False, config_file=_REACH)
    assert f"settings of `{_REACH}`" in path.read_text()
    for name in ("reference", "push", "payload", "uneven"):
        config = tomllib.loads(
            (tmp_path / "fig9" / "runs" / f"gaitnet-{name}" / CONFIG).read_text()
        )
        assert config["keep_feet_in_reach"] is True
