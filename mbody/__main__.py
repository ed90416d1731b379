"""`python -m mbody ...` runs the `mbody` command."""

import sys

from mbody.cli import main

sys.exit(main())
