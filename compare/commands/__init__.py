"""The command wing: one module per command in this package, each declaring a `Command` — its
arguments, its Python API function, its command-line handler, its Result type and its docs page.
`xval`'s parser (compare/cli.py) and the Python API's exports (compare/api.py, `import xval`)
are built from `COMMANDS`, so a new study is a module here (found by its file), its workflow,
its Result and its page — nothing else names it (ARCHITECTURE.md, "Add a study")."""
from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Arg:
    """One command-line argument: argparse's flags and keywords; arguments sharing an
    `exclusive` name exclude each other."""
    flags: tuple[str, ...]
    options: dict = field(default_factory=dict)
    exclusive: str | None = None


def arg(*flags, exclusive: str | None = None, **options) -> Arg:
    return Arg(flags, options, exclusive)


def add_args(parser, args) -> None:
    groups = {}
    for a in args:
        if a.exclusive is not None and a.exclusive not in groups:
            groups[a.exclusive] = parser.add_mutually_exclusive_group()
        target = parser if a.exclusive is None else groups[a.exclusive]
        target.add_argument(*a.flags, **a.options)


@dataclass(frozen=True)
class Command:
    """A command: `xval NAME ARGS` runs `main(args) -> exit status`; `api` is the same study
    from Python (exported by `xval` under its own name), returning a `result`; `docs` its page
    under docs/commands/; `order` its place in `xval --help`. `subcommands`: name -> (help,
    args) for a command with actions (`xval baseline save`)."""
    name: str
    help: str
    description: str
    main: Callable
    args: tuple = ()
    api: Callable | None = None
    result: type | None = None
    docs: str = ""
    order: int = 100
    subcommands: dict = field(default_factory=dict)


def names() -> list[str]:
    """Every command's name: its module's, found by file without importing any."""
    return [m.name for m in pkgutil.iter_modules(__path__)
            if not m.name.startswith("_") and m.name != "common"]


def command(name: str) -> Command:
    """One command, importing only its own module (a module's name is its command's)."""
    c = importlib.import_module(f"{__name__}.{name}").COMMAND
    assert c.name == name, f"compare/commands/{name}.py declares command {c.name!r}"
    return c


def _discover() -> dict[str, Command]:
    return {c.name: c for c in sorted(map(command, names()), key=lambda c: (c.order, c.name))}


def __getattr__(attr):
    # COMMANDS on first use: `xval run` imports run.py alone, not every command's wing
    if attr == "COMMANDS":
        globals()["COMMANDS"] = _discover()
        return globals()["COMMANDS"]
    raise AttributeError(f"module {__name__!r} has no attribute {attr!r}")


def api_functions() -> dict[str, Callable]:
    """The Python API: every command's function under its own name."""
    from . import COMMANDS
    return {c.api.__name__: c.api for c in COMMANDS.values() if c.api is not None}
