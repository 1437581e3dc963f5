"""``python -m experiments.fit_score``: see :mod:`experiments.fit_score`."""
import sys

from experiments.fit_score.cli import main

sys.exit(main())
