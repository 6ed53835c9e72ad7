"""`python -m stabctl`: the `stabctl` command (as `python -m stabctl.cli`)."""

from stabctl.cli import main

if __name__ == "__main__":  # pragma: no cover
    main()
