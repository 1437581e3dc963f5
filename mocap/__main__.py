"""``python -m mocap``: see :mod:`mocap.cli`."""
import sys

from mocap.cli import main

if __name__ == "__main__":
    sys.exit(main())
