"""mkdocs hooks: pages made from their single sources when the site is built, so they cannot
drift from what runs.

- A tutorial is a notebook kept as text (jupytext py:percent, `docs/tutorials/*.py`, which the
  tests execute); its page is that notebook converted to Markdown.
- `<!-- xval-help: COMMAND -->` in a page becomes `xval COMMAND --help` (`<!-- xval-help: -->`:
  `xval --help`): compare/cli.py is the one place the options are written.
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


def on_files(files, config):
    for src in TUTORIALS:
        md = tutorial_markdown(Path(config["docs_dir"]) / src)
        files.append(File.generated(config, src[:-len(".py")] + ".md", content=md))
    return files


def command_help(command: str) -> str:
    """`xval COMMAND --help` as this checkout's compare/cli.py prints it, 100 columns wide."""
    root = str(Path(__file__).resolve().parents[1])
    if root not in sys.path:
        sys.path.insert(0, root)
    os.environ["COLUMNS"] = "100"
    from compare.cli import build_parser
    parser = build_parser()
    for word in command.split():
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[word]
    return parser.format_help().rstrip()


def on_page_markdown(markdown, page, config, files):
    return HELP.sub(lambda m: f"```text\n{command_help(m.group(1))}\n```", markdown)
