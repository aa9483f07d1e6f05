"""``python -m pytest_emrd.cli`` runs the ``emrd`` console script."""

import sys

from pytest_emrd.cli import main

sys.exit(main())
