"""``gaitnet-mpc``: the parser of every sub-command, and the exit codes.

Exit codes (:data:`EXIT_CODES`, listed in ``--help`` and the README):

* 0 done;
* 1 the robot fell (``run``; ``--allow-fall`` makes a fall exit 0);
* 2 bad input: a named error (field, value, what was expected), found before any work;
* 3 part of the work failed (e.g. a set of ``collect`` raised in its worker): what did
  not fail is on disk, the failures are in the job's log and ``status.json``;
* 4 internal error: an exception this package did not expect (a bug; the traceback is
  printed);
* 130 interrupted (Ctrl-C or SIGTERM, at any time, start-up included): what was
  finished is on disk, ``status.json`` says what is left, the same command resumes.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
from collections.abc import Iterator
from types import ModuleType

from gaitnet_mpc.errors import GaitNetMPCError, PartialFailure, caused_by_interrupt

#: The sub-commands, in the order ``--help`` lists them: name -> module of ``cli/``.
COMMANDS = (
    "run",
    "plot",
    "compare",
    "collect",
    "train",
    "reproduce",
    "bench",
    "dataset",
    "sweep",
)

EXIT_OK, EXIT_FELL, EXIT_BAD_INPUT, EXIT_PART_FAILED, EXIT_INTERNAL = 0, 1, 2, 3, 4
EXIT_INTERRUPTED = 130
#: Every exit code and what it means (``--help``, README).
EXIT_CODES: dict[int, str] = {
    EXIT_OK: "done",
    EXIT_FELL: "the robot fell (run; --allow-fall: 0)",
    EXIT_BAD_INPUT: "bad input (a named error, before any work)",
    EXIT_PART_FAILED: "part of the work failed (see the job's log and status.json)",
    EXIT_INTERNAL: "internal error (a bug: the traceback is printed)",
    EXIT_INTERRUPTED: "interrupted (Ctrl-C / SIGTERM; what was done is kept, rerun to resume)",
}


def _module(name: str) -> ModuleType:
    return importlib.import_module(f"gaitnet_mpc.cli.{name}")


def build_parser() -> argparse.ArgumentParser:
    """The ``gaitnet-mpc`` parser with every sub-command."""
    return _build()[0]


def parse_args(argv: list[str]) -> argparse.Namespace:
    """The options of ``argv``. An option the sub-command does not know is its parser's
    error (its usage line, exit 2), not the top-level parser's."""
    parser, commands = _build()
    args, unknown = parser.parse_known_args(argv)
    if unknown:
        before = argv[: argv.index(args.cmd)] if args.cmd in argv else []
        owner = parser if any(u in before for u in unknown) else commands[args.cmd]
        owner.error(f"unrecognized arguments: {' '.join(unknown)}")
    return args


def _build() -> tuple[argparse.ArgumentParser, dict[str, argparse.ArgumentParser]]:
    """The ``gaitnet-mpc`` parser and each sub-command's parser by name."""
    from gaitnet_mpc import __version__

    modules = {name: _module(name) for name in COMMANDS}
    summary = "\n".join(f"  {name:<10} {modules[name].SUMMARY}" for name in COMMANDS)
    codes = "\n".join(f"  {code:<10} {text}" for code, text in EXIT_CODES.items())
    parser = argparse.ArgumentParser(
        prog="gaitnet-mpc",
        description="Gait-Net-augmented implicit kino-dynamic MPC for variable-frequency "
        "humanoid walking over discrete terrain (MuJoCo).",
        epilog=f"sub-commands:\n{summary}\n\nexit codes:\n{codes}\n\n"
        "`gaitnet-mpc SUB-COMMAND --help` for each one's options.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"gaitnet-mpc {__version__}")
    sub = parser.add_subparsers(dest="cmd", required=True, metavar="SUB-COMMAND")
    for name in COMMANDS:
        modules[name].add_parser(sub)
    return parser, {name: sub.choices[name] for name in COMMANDS}


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """Hold SIGINT and SIGTERM back while the block runs; deliver them after it.

    The block imports the sub-commands and what they need (MuJoCo, Pinocchio, the QP
    solvers). A signal that lands inside a compiled extension's initialisation comes out
    as some other error of that extension (``ImportError('initialization failed')``,
    ``ctypes.ArgumentError``), or leaves CPython flagged to kill itself; held back, it is
    delivered when the imports are done and stops the command as a plain Ctrl-C.
    """
    held = {signal.SIGINT, signal.SIGTERM}
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def main(argv: list[str] | None = None) -> int:
    """Run one sub-command; return its exit code (:data:`EXIT_CODES`)."""
    from gaitnet_mpc.parallel import stop_signals_as_keyboard_interrupt

    # Offscreen rendering backend; must be chosen before mujoco is first imported.
    os.environ.setdefault("MUJOCO_GL", "egl")
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        # SIGTERM stops every command as Ctrl-C does, from start-up through its last write
        with stop_signals_as_keyboard_interrupt():
            with _signals_deferred():
                args = parse_args(argv)
                command = _module(args.cmd)
                for name in getattr(command, "PRELOAD", ()):
                    importlib.import_module(name)
            args.argv = argv
            return int(command.main(args))
    except PartialFailure as exc:
        print(f"gaitnet-mpc: {exc}", file=sys.stderr)
        return EXIT_PART_FAILED
    except GaitNetMPCError as exc:
        print(f"gaitnet-mpc: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        # what a command had finished is already on disk (every file is written atomically)
        print("gaitnet-mpc: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:
        if caused_by_interrupt(exc):  # an import that a signal cut short
            print("gaitnet-mpc: interrupted", file=sys.stderr)
            return EXIT_INTERRUPTED
        import traceback

        traceback.print_exc()
        print(
            "gaitnet-mpc: internal error (a bug, please report it with the traceback above)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


def entry() -> None:
    """The ``gaitnet-mpc`` executable: :func:`main`, then exit with its code.

    After an interrupt the process ends with :func:`os._exit` (streams flushed; every
    file was written and every lock released before :func:`main` returned): an interrupt
    that cut short an extension's start-up inside CPython's ``PyRun_*`` leaves the
    interpreter flagged to kill itself with SIGINT at exit, which would replace exit
    code 130 by -2.
    """
    code = main()
    if code == EXIT_INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    entry()
