"""`python -m mbody ...` runs the `mbody` command."""

import sys

from .cli import main

sys.exit(main())
