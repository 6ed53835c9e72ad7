"""`python -m stabctl.cli`: the `stabctl` command."""

from stabctl.cli import main

if __name__ == "__main__":  # pragma: no cover
    main()
