"""MuJoCo's interactive viewer for ``gaitnet-mpc run --viewer``: a check that a window can
open, and the viewer on a simulator with its camera tracking the trunk."""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING, Any

from gaitnet_mpc.errors import ConfigError, reraise_interrupt

if TYPE_CHECKING:
    from gaitnet_mpc.sim.simulator import Simulator


def _has_display() -> bool:
    """Whether an interactive window can be opened (X11 or Wayland on Linux)."""
    if not sys.platform.startswith("linux"):
        return True  # macOS / Windows: the viewer reports its own requirements
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _glfw_can_open() -> str | None:
    """None if GLFW (the viewer's window library) initialises, else the reason it did not.

    Probed here because ``mujoco.viewer.launch_passive`` initialises GLFW in a thread and
    waits forever when that fails (e.g. ``DISPLAY`` set but no X server reachable).
    """
    import warnings

    try:
        import glfw
    except ImportError as exc:  # pragma: no cover - glfw is a mujoco dependency
        reraise_interrupt(exc)
        return f"the glfw package is missing ({exc})"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ok = glfw.init()
    if ok:
        glfw.terminate()
        return None
    return "; ".join(str(w.message) for w in caught) or "glfw.init() failed"


def check_viewer() -> None:
    """Fail fast when ``--viewer`` cannot open a window."""
    if not _has_display():
        raise ConfigError(
            "--viewer",
            "no display (DISPLAY and WAYLAND_DISPLAY are unset)",
            "a graphical session for MuJoCo's interactive viewer; without one, drop "
            "--viewer and watch video.mp4 (rendered offscreen)",
        )
    if sys.platform.startswith("linux"):
        reason = _glfw_can_open()
        if reason is not None:
            display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
            raise ConfigError(
                "--viewer",
                f"display {display!r} ({reason})",
                "a display the viewer can open; without one, drop --viewer and watch "
                "video.mp4 (rendered offscreen)",
            )


def open_viewer(sim: Simulator) -> Any:
    """MuJoCo's passive viewer on the simulator, its camera tracking the trunk."""
    import mujoco
    import mujoco.viewer

    handle = mujoco.viewer.launch_passive(sim.model, sim.data)
    with handle.lock():
        handle.cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        handle.cam.trackbodyid = sim.model.body(sim.robot.spec.trunk_body).id
        handle.cam.distance = 2.5
    return handle
