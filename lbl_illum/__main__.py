"""``python -m lbl_illum`` runs the command line."""

import sys

from .cli.main import main

sys.exit(main())
