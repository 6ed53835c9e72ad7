"""The `stabctl` command line (click): the group and one module per command family."""

from stabctl.cli.commands import main

__all__ = ["main"]
