from stabctl.cli.commands import main  # noqa: F401
