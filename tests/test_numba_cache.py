"""The compiled kernels' disk cache cannot go stale (mocap/_numba.py).

A throwaway package with two kernel modules, the second calling the first, is compiled in one
process and run from the cache in the next: editing only the first module must change what the
second returns (Numba's own per-file stamp would load the stale machine code), and an unchanged
tree must load from the cache.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from mocap._numba import compiled_sources_fingerprint

RUN = textwrap.dedent("""
    import json
    from kernels_pkg.caller import outer
    value = outer(2.0)
    print(json.dumps({"value": value, "hits": sum(outer.stats.cache_hits.values()),
                      "misses": sum(outer.stats.cache_misses.values())}))
""")


def _write_package(root: Path, constant: float) -> None:
    pkg = root / "kernels_pkg"
    pkg.mkdir(exist_ok=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "inner.py").write_text(textwrap.dedent(f"""
        from mocap._numba import jit

        @jit
        def scale(x):
            return x * {constant!r}
    """))
    (pkg / "caller.py").write_text(textwrap.dedent("""
        from mocap._numba import jit
        from kernels_pkg.inner import scale

        @jit
        def outer(x):
            return scale(x) + 1.0
    """))


def _run(root: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root), str(Path(__file__).resolve().parents[1])]))
    out = subprocess.run([sys.executable, "-c", RUN], cwd=root, env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_editing_a_called_kernel_invalidates_the_caller(tmp_path):
    _write_package(tmp_path, 3.0)
    first = _run(tmp_path)
    assert first["value"] == 7.0 and first["misses"] == 1
    again = _run(tmp_path)
    assert again["value"] == 7.0 and again["hits"] == 1          # unchanged tree: from the cache
    caller = tmp_path / "kernels_pkg" / "caller.py"
    before = caller.stat().st_mtime_ns
    _write_package(tmp_path, 5.0)                                 # rewrites inner.py (and caller.py identically)
    os.utime(caller, ns=(before, before))                         # the caller's own file looks untouched
    edited = _run(tmp_path)
    assert edited["value"] == 11.0 and edited["misses"] == 1      # recompiled, not the stale 7.0


def test_fingerprint_covers_kernel_modules_and_what_they_import(tmp_path):
    _write_package(tmp_path, 3.0)
    (tmp_path / "kernels_pkg" / "unrelated.py").write_text("X = 1\n")
    root = str(tmp_path / "kernels_pkg")
    base = compiled_sources_fingerprint(root)
    (tmp_path / "kernels_pkg" / "unrelated.py").write_text("X = 2\n")
    compiled_sources_fingerprint.cache_clear()
    assert compiled_sources_fingerprint(root) == base             # not a kernel's source
    (tmp_path / "kernels_pkg" / "inner.py").write_text((tmp_path / "kernels_pkg" / "inner.py").read_text() + "\n# edit\n")
    compiled_sources_fingerprint.cache_clear()
    assert compiled_sources_fingerprint(root) != base


def test_the_gradient_steps_compiled_callees_are_fingerprinted():
    # optimize.py's Gauss-Newton loop compiles the gradient kernels of cost.py, the joint
    # Jacobians of body/kinematics.py and the edge scan of render/rasterize.py into itself: each
    # of those files must be part of the fingerprint, or an edit to it would leave the loop stale
    import mocap
    from mocap._numba import KERNEL_MARKER

    root = Path(mocap.__file__).parent
    for name in ("optimize.py", "cost.py", "body/kinematics.py", "render/rasterize.py", "render/_raster.py"):
        assert KERNEL_MARKER in (root / name).read_text(encoding="utf-8"), name
