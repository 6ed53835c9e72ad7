"""`python -m stabctl.cli ...`: the stabctl command line."""

from stabctl.cli import main

main()
