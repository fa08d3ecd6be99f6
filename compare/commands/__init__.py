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


def _discover() -> dict[str, Command]:
    found = []
    for info in pkgutil.iter_modules(__path__):
        if info.name.startswith("_") or info.name == "common":
            continue
        found.append(importlib.import_module(f"{__name__}.{info.name}").COMMAND)
    return {c.name: c for c in sorted(found, key=lambda c: (c.order, c.name))}


COMMANDS: dict[str, Command] = _discover()


def api_functions() -> dict[str, Callable]:
    """The Python API: every command's function under its own name."""
    return {c.api.__name__: c.api for c in COMMANDS.values() if c.api is not None}
