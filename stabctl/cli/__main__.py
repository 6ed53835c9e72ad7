"""`python -m stabctl.cli`: the `stabctl` command (`stabctl.__main__`)."""

from stabctl.__main__ import main

if __name__ == "__main__":  # pragma: no cover
    main()
