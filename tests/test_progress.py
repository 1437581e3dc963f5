"""Progress bars say "compiling" exactly while Numba compiles (mocap._progress)."""
from __future__ import annotations

import io

import numba

from mocap._progress import COMPILING_NOTE, ProgressBar, compiling_announced


def _fresh_kernel():
    """A kernel never compiled before (no cache): its first call compiles it."""
    @numba.njit
    def twice(x):
        return 2.0 * x
    return twice


def test_the_bar_says_compiling_while_a_kernel_compiles_and_not_after():
    out = io.StringIO()
    kernel = _fresh_kernel()
    labels = []
    bar = ProgressBar(total=2, desc="tracking", file=out, mininterval=0)
    original = bar.set_description
    bar.set_description = lambda desc=None, refresh=True: (labels.append(desc), original(desc, refresh))[1]
    try:
        assert kernel(1.5) == 3.0             # compiles: the label changes, then back
        bar.update(1)
        assert kernel(2.0) == 4.0             # compiled: no change
        bar.update(1)
    finally:
        bar.close()
    assert labels == [f"tracking ({COMPILING_NOTE})", "tracking"]
    assert f"tracking ({COMPILING_NOTE})" in out.getvalue()
    _fresh_kernel()(1.0)                      # a closed bar listens no more
    assert len(labels) == 2


def test_the_notice_is_printed_once_and_only_when_something_compiles(capsys):
    with compiling_announced(True, "the kernels"):
        _fresh_kernel()(1.0)
        _fresh_kernel()(1.0)
    assert capsys.readouterr().err.count("compiling the kernels (first run only") == 1
    kernel = _fresh_kernel()
    kernel(1.0)
    with compiling_announced(True):
        kernel(2.0)                           # compiled before: silent
    with compiling_announced(False):
        _fresh_kernel()(1.0)                  # not shown
    assert capsys.readouterr().err == ""
