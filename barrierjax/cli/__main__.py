"""`python -m barrierjax.cli`: the `barrierjax` command."""

import sys

from . import main

sys.exit(main())
