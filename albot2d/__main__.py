"""``python -m albot2d`` runs the CLI."""

import sys

from albot2d.cli import main

sys.exit(main())
