"""`python -m stabctl`: the `stabctl` command (signals handled from the start:
`stabctl._entry`)."""

from stabctl._entry import main

if __name__ == "__main__":  # pragma: no cover
    main()
