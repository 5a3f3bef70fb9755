"""``python -m swarmshape`` runs the command line."""

import sys

from swarmshape.cli import main

sys.exit(main())
