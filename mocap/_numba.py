"""The one place where Numba compilation flags are set.

Every compiled kernel in the package is decorated with :data:`jit` so that caching, fastmath
and the GIL policy are decided here and nowhere else.
"""
from __future__ import annotations

import functools

import numba

#: Decorator for every compiled kernel: on-disk cache (cold compile takes seconds),
#: no GIL so kernels can run in threads, no fastmath (NaN/inf semantics must hold).
jit = functools.partial(numba.njit, cache=True, nogil=True, fastmath=False)
