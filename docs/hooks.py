"""mkdocs hooks: pages made from their single sources when the site is built, so they cannot
drift from what runs.

- A tutorial is a notebook kept as text (jupytext py:percent, `docs/tutorials/*.py`, which the
  tests execute); its page is that notebook converted to Markdown.
- `<!-- xval-help: COMMAND -->` in a page becomes `xval COMMAND --help` (`<!-- xval-help: -->`:
  `xval --help`): compare/commands/ is the one place the options are written.
- The Commands section of the navigation lists every command's page from the registry, in
  `xval --help`'s order: a new command's page needs no line in mkdocs.yml.
"""
import argparse
import os
import re
import sys
from pathlib import Path

import jupytext
from mkdocs.structure.files import File

TUTORIALS = ("tutorials/own_system.py",)
HELP = re.compile(r"<!-- xval-help:([a-z ]*)-->")


def tutorial_markdown(path) -> str:
    """The notebook at `path` as Markdown, without jupytext's metadata header."""
    nb = jupytext.read(path)
    nb.metadata = {"jupytext": {"notebook_metadata_filter": "-all"}}
    return jupytext.writes(nb, fmt="md")


def _checkout_on_path():
    root = str(Path(__file__).resolve().parents[1])
    if root not in sys.path:
        sys.path.insert(0, root)


def on_config(config):
    _checkout_on_path()
    from compare.commands import COMMANDS
    pages = {}
    for c in COMMANDS.values():
        pages.setdefault(f"commands/{c.docs}", []).append(c.name)
    for section in config["nav"]:
        if isinstance(section, dict) and "Commands" in section:
            entries = section["Commands"]
            given = {next(iter(e.values())) if isinstance(e, dict) else e for e in entries}
            tail = entries.index(next(e for e in entries if isinstance(e, dict)
                                      and "contract.md" in e.values()))
            entries[tail:tail] = [{" and ".join(names): page} for page, names in pages.items()
                                  if page not in given]
    return config


def on_files(files, config):
    for src in TUTORIALS:
        md = tutorial_markdown(Path(config["docs_dir"]) / src)
        files.append(File.generated(config, src[:-len(".py")] + ".md", content=md))
    return files


def command_help(command: str) -> str:
    """`xval COMMAND --help` as this checkout's compare/cli.py prints it, 100 columns wide."""
    _checkout_on_path()
    os.environ["COLUMNS"] = "100"
    from compare.cli import build_parser
    parser = build_parser()
    for word in command.split():
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[word]
    return parser.format_help().rstrip()


def on_page_markdown(markdown, page, config, files):
    return HELP.sub(lambda m: f"```text\n{command_help(m.group(1))}\n```", markdown)
