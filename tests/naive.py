"""Slow, obviously-correct pure-NumPy twins of the compiled kernels.

Every ``@jit`` kernel in :mod:`mocap` is compared against its twin here in the tests.
Sections: rendering, costs, imaging.
"""
from __future__ import annotations

import numpy as np

# --- imaging ---
