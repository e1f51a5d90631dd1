"""`python -m harness COMMAND …`: the command line lives in harness/cli/main.py."""

import sys

from harness.cli.main import main

sys.exit(main())
