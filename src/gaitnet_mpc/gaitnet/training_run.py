"""``gaitnet-mpc train`` into a model folder: checked before work, resumable member by
member, written atomically.

While it trains, a hidden sibling folder ``.<out>.training/`` (locked: one ``train`` at a
time) holds ``resume.json`` (what is being trained: the data set's manifest hash, the
features, the settings and the split seed), ``member-K.npz`` for each finished ensemble
member, and ``status.json`` (members done and to do). When every member is done, the
results are written to ``.<out>.training/result/`` and renamed into place as ``<out>``,
and the hidden folder is removed. So:

* ``<out>`` appears whole or not at all, and an existing model is replaced only with
  ``overwrite``;
* interrupted (Ctrl-C, SIGTERM, a kill) at any time, the same command resumes from the
  finished members; members are independent (each from its own seed), so the weights
  equal those of a training that was not interrupted;
* a training with other data or settings into the same ``<out>`` starts afresh.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gaitnet.data import load_dataset
from gaitnet_mpc.gaitnet.fit import FitReport, feature_subset, fit, write_fit
from gaitnet_mpc.gaitnet.model import WEIGHTS_FILE
from gaitnet_mpc.gaitnet.train import MemberFit, TrainConfig
from gaitnet_mpc.results.io import write_json_atomic
from gaitnet_mpc.results.outdir import (
    check_output_path,
    check_writable,
    folder_lock,
    write_status,
)

#: Files of a model folder (what ``overwrite`` may replace).
MODEL_FILES = (WEIGHTS_FILE, "report.json", "loss.csv", "loss.png", "fig4.png")
RESUME = "resume.json"


def staging_folder(out: Path) -> Path:
    """The hidden folder a training into ``out`` works in."""
    return out.parent / f".{out.name}.training"


def check_model_out(out: str | Path, overwrite: bool) -> Path:
    """``out`` as a folder a model may be written to: new, empty, or (``overwrite``) one
    holding only an earlier model's files; writable, in a writable parent (where the
    training works, :func:`staging_folder`, and from where the model is renamed into
    place), all checked before any training."""
    path = check_output_path(out, "--out")
    if path.is_dir():  # else check_output_path probed the parent already
        check_writable(path.parent, "--out", shown=path)
    if path.is_dir():
        names = sorted(p.name for p in path.iterdir())
        foreign = [n for n in names if n not in MODEL_FILES]
        if names and not overwrite:
            raise ConfigError(
                "--out",
                str(path),
                f"a new or empty folder (it holds {', '.join(names[:4])}); pass --overwrite "
                "to replace the model in it",
            )
        if foreign:
            raise ConfigError(
                "--out",
                str(path),
                f"a folder holding only an earlier model (it also holds {', '.join(foreign[:4])})",
            )
    return path


def train_folder(
    data_dir: Path,
    out: Path,
    features: str,
    config: TrainConfig,
    split_seed: int,
    *,
    overwrite: bool = False,
    progress: bool = True,
    command: str = "",
    log: Callable[[str], None] = print,
) -> FitReport:
    """Train on the data set ``data_dir`` and write the model folder ``out``.

    Raises:
        ConfigError: bad input (found before any training), or another ``train`` holds
            the same ``out``.
        KeyboardInterrupt: on Ctrl-C / SIGTERM, after writing the status file.
    """
    out = check_model_out(out, overwrite)
    feature_subset(features)  # a bad --features fails before any training
    data = load_dataset(data_dir)
    identity = {
        "data_manifest_sha256": data.manifest_sha256,
        "features": features,
        "config": asdict(config),
        "split_seed": split_seed,
    }
    identity = json.loads(json.dumps(identity))  # tuples as lists, as read back
    staging = staging_folder(out)
    all_members = [f"member {k}" for k in range(config.members)]
    with folder_lock(staging, what="train"):
        done = _finished_members(staging, identity, config.members, log)
        write_json_atomic(staging / RESUME, identity)

        def status(state: str, code: int | None = None) -> None:
            finished = [f"member {k}" for k in sorted(done)]
            write_status(
                staging,
                command=command,
                state=state,
                exit_code=code,
                done=finished,
                todo=[m for m in all_members if m not in finished],
                note=f"the model goes to {out} when every member is trained; run the same "
                "command again to resume",
            )

        def keep(member: int, fit_: MemberFit) -> None:
            fit_.save(staging / f"member-{member}.npz")
            done[member] = fit_
            status("running")

        status("running")
        try:
            result, report, selection = fit(
                data,
                features,
                config,
                split_seed=split_seed,
                progress=progress,
                done=dict(done),
                on_member=keep,
            )
        except KeyboardInterrupt:
            status("interrupted", 130)
            log(f"interrupted: {len(done)} of {config.members} members are kept in {staging}")
            raise
        result_dir = staging / "result"
        if result_dir.exists():
            shutil.rmtree(result_dir)
        write_fit(result_dir, result, report, selection)
        if out.exists():
            out.rename(staging / "previous")  # an earlier model (checked: overwrite) or empty
        result_dir.rename(out)
        shutil.rmtree(staging)
    return report


def _finished_members(
    staging: Path, identity: dict[str, Any], members: int, log: Callable[[str], None]
) -> dict[int, MemberFit]:
    """The members a training of the same ``identity`` left in ``staging``."""
    path = staging / RESUME
    if not path.is_file():
        return {}
    try:
        before = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        before = None
    if before != identity:
        for old in staging.glob("member-*.npz"):
            old.unlink()
        log(f"{staging}: checkpoints of another training (other data or settings) discarded")
        return {}
    done = {}
    for k in range(members):
        file = staging / f"member-{k}.npz"
        if file.is_file():
            try:
                done[k] = MemberFit.load(file)
            except (OSError, ValueError, KeyError) as exc:
                log(f"{file.name}: unreadable ({exc}); training member {k} again")
    if done:
        log(f"resuming: members {sorted(done)} of {members} are already trained in {staging}")
    return done
