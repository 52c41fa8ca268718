"""``gaitnet-mpc``: the parser of every sub-command, and the exit codes.

Exit codes: 0 done (a run that ends in a fall is done: its outcome line says FELL), 2 bad
input (a named error: field, value, what was expected), 130 interrupted (Ctrl-C or
SIGTERM; what was finished is on disk).
"""

from __future__ import annotations

import argparse
import os
import sys
from types import ModuleType

from gaitnet_mpc.errors import GaitNetMPCError

#: The sub-commands, in the order ``--help`` lists them: name -> module of ``cli/``.
COMMANDS = ("run", "plot", "compare", "collect", "train", "reproduce", "bench", "dataset")

EXIT_OK, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 2, 130


def _module(name: str) -> ModuleType:
    import importlib

    return importlib.import_module(f"gaitnet_mpc.cli.{name}")


def build_parser() -> argparse.ArgumentParser:
    """The ``gaitnet-mpc`` parser with every sub-command."""
    from gaitnet_mpc import __version__

    modules = {name: _module(name) for name in COMMANDS}
    summary = "\n".join(f"  {name:<10} {modules[name].SUMMARY}" for name in COMMANDS)
    parser = argparse.ArgumentParser(
        prog="gaitnet-mpc",
        description="Gait-Net-augmented implicit kino-dynamic MPC for variable-frequency "
        "humanoid walking over discrete terrain (MuJoCo).",
        epilog=f"sub-commands:\n{summary}\n\nexit codes: 0 done (a run that falls is done; "
        "its last line says FELL), 2 bad input, 130 interrupted.\n"
        "`gaitnet-mpc SUB-COMMAND --help` for each one's options.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"gaitnet-mpc {__version__}")
    sub = parser.add_subparsers(dest="cmd", required=True, metavar="SUB-COMMAND")
    for name in COMMANDS:
        modules[name].add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    # Offscreen rendering backend; must be chosen before mujoco is first imported.
    os.environ.setdefault("MUJOCO_GL", "egl")
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        args = build_parser().parse_args(argv)
    except KeyboardInterrupt:
        print("gaitnet-mpc: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    args.argv = argv
    command = _module(args.cmd)
    try:
        if args.cmd == "run":
            # SIGTERM and SIGINT stop a run like Ctrl-C, from start-up through plotting
            from gaitnet_mpc.parallel import stop_signals_as_keyboard_interrupt

            with stop_signals_as_keyboard_interrupt():
                return int(command.main(args))
        return int(command.main(args))
    except GaitNetMPCError as exc:
        print(f"gaitnet-mpc: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        # Ctrl-C outside the simulation loop (start-up, plotting, training); what a
        # command had finished is already on disk (every file is written atomically)
        print("gaitnet-mpc: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
