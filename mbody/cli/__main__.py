"""`python -m mbody.cli ...` runs the `mbody` command (as `python -m mbody` does)."""

import sys

from mbody.cli.app import main

sys.exit(main())
