"""The one place where Numba compilation flags and the on-disk cache's freshness are decided.

Every compiled kernel in the package is decorated with :data:`jit` so that caching, fastmath
and the GIL policy are decided here and nowhere else.

**Why a cache of our own.** Numba's ``cache=True`` keys a function's cached machine code on the
modification time and size of *its own* source file only. A kernel that calls another module's
kernel (``optimize.py``'s simplex loop compiles the cost kernels of ``cost.py`` into itself)
or reads another module's constants would be loaded stale from disk after that other module
was edited. Here the freshness stamp of every kernel is its own file's stamp *plus* a
fingerprint of the package's compiled sources: every module that defines kernels and every
package module those import from. Editing any of them invalidates every cached kernel, so
stale machine code cannot be loaded; a fresh clone or an unchanged tree loads from the cache.
"""
from __future__ import annotations

import ast
import functools
import hashlib
from pathlib import Path

import numba
from numba.core.caching import (CompileResultCacheImpl, FunctionCache, InTreeCacheLocator,
                                UserWideCacheLocator)

#: Text by which a module is recognised as defining compiled kernels.
KERNEL_MARKER = "_numba import jit"


def _package_root(py_file: str) -> Path:
    """The top-level package folder containing ``py_file`` (its outermost folder with an ``__init__.py``)."""
    folder = Path(py_file).resolve().parent
    root = folder
    while (folder / "__init__.py").is_file():
        root = folder
        folder = folder.parent
    return root


def _imported_modules(path: Path, package: str) -> set[str]:
    """Dotted names of the ``package`` modules that ``path`` imports from."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0 and node.module.split(".")[0] == package:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names)      # "from pkg.sub import module"
        elif isinstance(node, ast.Import):
            names.update(a.name for a in node.names if a.name.split(".")[0] == package)
    return names


@functools.lru_cache(maxsize=None)
def compiled_sources_fingerprint(root: str) -> str:
    """SHA-256 over the package's compiled sources (see the module): hex digest.

    Parameters
    ----------
    root : str
        The package folder (:func:`_package_root`).
    """
    root_path = Path(root)
    package = root_path.name
    files = sorted(root_path.rglob("*.py"))
    kernels = [f for f in files if KERNEL_MARKER in f.read_text(encoding="utf-8")]
    used = set(kernels)
    for f in kernels:
        for dotted in _imported_modules(f, package):
            relative = Path(*dotted.split(".")[1:])
            for candidate in (root_path / relative.with_suffix(".py"), root_path / relative / "__init__.py"):
                if candidate.is_file():
                    used.add(candidate)
    digest = hashlib.sha256()
    for f in sorted(used):
        digest.update(str(f.relative_to(root_path)).encode())
        digest.update(f.read_bytes())
    return digest.hexdigest()


class _FingerprintStamp:
    """Locator mixin: the source stamp also carries the package's compiled-sources fingerprint."""

    def get_source_stamp(self):
        return (super().get_source_stamp(), compiled_sources_fingerprint(str(_package_root(self._py_file))))


class _InTreeLocator(_FingerprintStamp, InTreeCacheLocator):
    pass


class _UserWideLocator(_FingerprintStamp, UserWideCacheLocator):
    pass


class _KernelCacheImpl(CompileResultCacheImpl):
    _locator_classes = [_InTreeLocator, _UserWideLocator]


class _KernelCache(FunctionCache):
    _impl_class = _KernelCacheImpl


def jit(py_func):
    """Compile ``py_func`` in nopython mode: no GIL (kernels can run in threads), no fastmath
    (NaN/inf semantics must hold), cached on disk with the package-wide freshness stamp above
    (cold compiles take seconds)."""
    dispatcher = numba.njit(nogil=True, fastmath=False)(py_func)
    dispatcher._cache = _KernelCache(py_func)        # what numba's own enable_caching() sets
    return dispatcher
