"""``python -m scatterlab``: the command-line interface (:func:`scatterlab.cli.main`)."""

import sys

from scatterlab.cli import main

if __name__ == "__main__":  # importing the module (doctest collection, docs) must not run the CLI
    sys.exit(main())
