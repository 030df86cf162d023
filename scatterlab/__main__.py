"""``python -m scatterlab``: the command-line interface (:func:`scatterlab.cli.main`)."""

import sys

from scatterlab.cli import main

sys.exit(main())
