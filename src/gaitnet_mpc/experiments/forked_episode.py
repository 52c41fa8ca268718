"""An episode simulated once up to a disturbance and finished in forked copies of itself.

A push sweep's bisection runs the same episode again and again with a different push
force: every run walks the same settling time (3 s or more) before the push starts, and the
simulation and controller are deterministic, so those seconds are the same every time.
:class:`ForkedEpisode` simulates them once, then finishes each variant in a child process
made by ``os.fork``: a copy of the whole process (simulator, controller, solver workspaces,
logs) at the moment before the push, in which the push is set and the episode runs to its
end. The parent never steps past the shared prefix, so every child starts from the same
state, bit for bit, as a fresh episode with that push would have reached it.

Where ``os.fork`` is missing (Windows) or unsafe (inside a Ray worker), :func:`fork_usable`
is False and callers run whole episodes instead; the results are the same, only slower.
"""

from __future__ import annotations

import json
import os
import sys
import time
import traceback
from collections.abc import Callable
from typing import Any, NoReturn

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.runner.loop import EpisodeLoop
from gaitnet_mpc.scenario.model import Episode


def fork_usable() -> bool:
    """Whether this process may fork a copy of itself to finish an episode: POSIX, and not
    a Ray worker (Ray's threads and sockets do not survive a fork)."""
    if not hasattr(os, "fork"):
        return False
    ray = sys.modules.get("ray")
    return ray is None or not ray.is_initialized()


class ForkedEpisode:
    """``episode`` (built without the variants' disturbances) simulated until ``prefix_s``;
    :meth:`finish` runs the rest with given pushes in a forked child.

    Args:
        episode: from :func:`~gaitnet_mpc.scenario.build_episode`, not yet stepped.
        duration_s: the whole episode's simulated time [s] (as ``run_episode``'s).
        prefix_s: the shared prefix [s]: ticks are simulated while the clock is below it,
            so the first tick of a child starts at ``prefix_s`` (to half a timestep).

    Attributes:
        prefix_wall_s: wall time of the prefix [s].
    """

    def __init__(self, episode: Episode, duration_s: float, prefix_s: float) -> None:
        if not (0.0 <= prefix_s < duration_s):
            raise ConfigError("prefix_s", prefix_s, f"a time in [0, {duration_s:g}) s")
        self.episode = episode
        sim = episode.sim
        t0 = time.perf_counter()
        self.loop = EpisodeLoop(sim, episode.controller, episode.scenario.command, duration_s)
        half_tick = 0.5 * sim.config.timestep_s
        while not self.loop.done and sim.time_s < prefix_s - half_tick:
            self.loop.tick()
        self.prefix_wall_s = time.perf_counter() - t0

    def finish(
        self, pushes: tuple[Any, ...], outcome: Callable[[EpisodeLoop, float], dict[str, Any]]
    ) -> dict[str, Any]:
        """Set ``pushes`` (each starting at or after the prefix) in a forked copy, run it
        to the end, and return ``outcome(loop, wall_s)`` computed there (JSON-ready;
        ``wall_s``: the child's simulated part only).

        Raises:
            RuntimeError: the child failed; its traceback is in the message.
        """
        read_fd, write_fd = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: never returns
            os.close(read_fd)
            reply_and_exit(write_fd, lambda: self._run_child(pushes, outcome))
        os.close(write_fd)
        return read_reply(pid, read_fd, "a forked episode")

    def _run_child(
        self, pushes: tuple[Any, ...], outcome: Callable[[EpisodeLoop, float], dict[str, Any]]
    ) -> dict[str, Any]:
        loop = self.loop
        loop.sim.set_pushes(pushes)
        t0 = time.perf_counter()
        while not loop.done:
            loop.tick()
        return outcome(loop, time.perf_counter() - t0)


def reply_and_exit(write_fd: int, compute: Callable[[], dict[str, Any]]) -> NoReturn:
    """In a forked child: send ``compute()`` (JSON-ready) to the parent through
    ``write_fd``, or the traceback of whatever it raised, and end the process."""
    code = 0
    payload: dict[str, Any]
    try:
        payload = {"ok": compute()}
    except BaseException:  # everything, KeyboardInterrupt too, goes to the parent
        payload, code = {"error": traceback.format_exc()}, 1
    with os.fdopen(write_fd, "wb") as pipe:
        pipe.write(json.dumps(payload).encode())
    os._exit(code)


def read_reply(pid: int, read_fd: int, what: str) -> dict[str, Any]:
    """In the parent: the reply of child ``pid`` (:func:`reply_and_exit`) read from
    ``read_fd``, after the child ended.

    Raises:
        RuntimeError: the child failed (its traceback in the message) or sent nothing.
    """
    with os.fdopen(read_fd, "rb") as pipe:
        data = pipe.read()
    _, status = os.waitpid(pid, 0)
    reply = json.loads(data) if data else {}
    if "ok" not in reply:
        detail = reply.get("error") or f"exit status {status}, no reply"
        raise RuntimeError(f"{what} failed:\n{detail}")
    return dict(reply["ok"])
