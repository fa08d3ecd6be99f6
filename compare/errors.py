"""Errors the CLI turns into exit statuses."""


class BadInput(ValueError):
    """Unknown name, malformed or out-of-range value: one line, exit status 2, nothing run."""
