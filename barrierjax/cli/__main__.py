"""`python -m barrierjax.cli`: the `barrierjax` command."""

from . import command

command()
