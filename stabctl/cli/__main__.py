"""`python -m stabctl.cli`: the `stabctl` command (`stabctl._entry`)."""

from stabctl._entry import main

if __name__ == "__main__":  # pragma: no cover
    main()
