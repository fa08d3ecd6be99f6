"""`xval`: the command-line contract (see the README and docs/contract.md), built from the
command registry (compare/commands/: each command's arguments and handler).

Exit status: 0 every requested run finished, 1 a verdict is `disagree` or `inconclusive` and
--strict was given, 2 bad input (one line on stderr, nothing run, nothing written), 3 a solver
crashed.
"""
import argparse
import os
import sys

from .errors import BadInput


class _Parser(argparse.ArgumentParser):
    def error(self, message):                      # one line, status 2 (not argparse's usage)
        raise BadInput(message)


def version() -> str:
    """The installed distribution's version (pyproject.toml's, as pip installed it)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version
    try:
        return dist_version("xval")
    except PackageNotFoundError:                  # a clone used without `pip install`
        return "unknown (not installed: pip install -e .)"


def build_parser(only: str | None = None):
    """The parser of every command, or of `only` (one command's module imported, not all)."""
    from .commands import add_args, command
    p = _Parser(prog="xval", description="Cross-validate multibody dynamics solvers: the same "
                "scene through our implementations of published methods, Exudyn and MuJoCo, "
                "compared in numbers, plots and rerun recordings.",
                epilog="Exit status: 0 finished, 1 a verdict is disagree or inconclusive under "
                       "--strict, 2 bad input (one line, nothing run), 3 a solver crashed.")
    p.add_argument("--version", action="version", version=f"xval {version()}",
                   help="print the installed version and exit")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser,
                           metavar="COMMAND")
    if only is None:
        from .commands import COMMANDS
        chosen = COMMANDS.values()
    else:
        chosen = [command(only)]
    for c in chosen:
        sp = sub.add_parser(c.name, help=c.help, description=c.description)
        add_args(sp, c.args)
        if c.subcommands:
            actions = sp.add_subparsers(dest="action", required=True, parser_class=_Parser,
                                        metavar="ACTION",
                                        help=", ".join(c.subcommands) + " (the actions)")
            for name, (text, args) in c.subcommands.items():
                add_args(actions.add_parser(name, help=text), args)
    return p


def main(argv=None):
    import warnings
    # numba's performance hints are for us, noise for users (matched by module: importing numba
    # here to name the class would cost a second before every one-line answer)
    warnings.filterwarnings("ignore", module=r"numba(\.|$)")
    try:
        from .commands import command, names
        argv = list(sys.argv[1:] if argv is None else argv)
        named = next((a for a in argv if not a.startswith("-")), None)
        only = named if named in names() and argv[0] == named else None
        args = build_parser(only).parse_args(argv)
        args.argv = argv
        from .output.progress import reporting
        with reporting():              # studies' counters (maps, response, …) on stderr
            return command(args.command).main(args)
    except BadInput as e:
        print(f"xval: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:          # Ctrl-C outside a campaign's jobs: one line, no traceback
        print("xval: interrupted", file=sys.stderr)
        return 130


def entry():
    try:
        sys.exit(main())
    except BrokenPipeError:            # `xval list | head`: the reader left, nothing to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(0)
