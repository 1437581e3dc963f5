"""The import layers of the package (docs/design.md section 1), as an AST check.

Layers, low to high; a module may import its own layer and below:

0 base    ``mocap/_*.py``, ``mocap/labels.py``, ``mocap/config.py``, ``mocap/io/files.py``
1 body    ``mocap/body``
2 io      ``mocap/io`` (files of frames, poses, keypoints: the body model's names, nothing above)
3 render  ``mocap/render``
4 image   ``mocap/imaging``, ``mocap/cost.py``, ``mocap/metrics.py``
5 fit     ``mocap/optimize.py``
6 track   ``mocap/track*``, ``mocap/calibrat*``, ``mocap/synth`` (every other module of the package)
7 run     ``mocap/run`` (a source in, a run's files out), ``mocap/bench.py``
8 face    ``mocap/commands``, ``mocap/cli.py``, ``mocap/__main__.py``, ``experiments``, ``notebooks``, ``docs``

(The layers of ``../shared/tools/check_layers.py``.) A second rule: no module imports another
package's private names (``from mocap.x import _y``, ``import mocap.x._y``) — a private module
or name is used only inside the package that holds it.
"""
from __future__ import annotations

import ast
from pathlib import Path

LAYER_NAMES = ("base", "body", "io", "render", "image", "fit", "track", "run", "face")
_TOP = {"experiments", "notebooks", "docs"}
_BY_SUBPACKAGE = {"labels": 0, "config": 0, "body": 1, "io": 2, "render": 3, "imaging": 4, "cost": 4,
                  "metrics": 4, "optimize": 5, "run": 7, "bench": 7, "commands": 8, "cli": 8, "__main__": 8}
#: Layer of every other module of the package.
_DEFAULT = 6


def layer(module: str) -> int:
    """Layer (0..8) of a dotted module name of the project; -1 for other packages."""
    parts = module.split(".")
    if parts[0] in _TOP:
        return LAYER_NAMES.index("face")
    if parts[0] != "mocap" or len(parts) == 1:
        return -1
    sub = parts[1]
    if sub.startswith("_") and sub != "__main__":
        return 0
    if parts[1:3] == ["io", "files"]:        # atomic writes and JSON files: the bottom of the package
        return 0
    return _BY_SUBPACKAGE.get(sub, _DEFAULT)


def project_modules(root: Path) -> dict[str, Path]:
    """Dotted name -> file of every Python module under ``mocap/``, ``experiments/``, ``notebooks/``, ``docs/``."""
    out = {}
    for top in ("mocap", *sorted(_TOP)):
        for f in sorted((root / top).glob("**/*.py")):
            out[".".join(f.relative_to(root).with_suffix("").parts).removesuffix(".__init__")] = f
    return out


def _imports(tree: ast.AST):
    """(line, imported module, imported names) of every absolute import."""
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.lineno, node.module, [a.name for a in node.names]
        elif isinstance(node, ast.Import):
            for a in node.names:
                yield node.lineno, a.name, []


def _private_owner(module: str, names: list[str]) -> str | None:
    """The package that owns the first private part of ``module`` (+ ``names``), or None."""
    parts = module.split(".")
    for i, p in enumerate(parts):
        if p.startswith("_") and not p.startswith("__"):
            return ".".join(parts[:i])
    if any(n.startswith("_") and not n.startswith("__") for n in names):
        return module
    return None


def violations(root: str | Path) -> list[str]:
    """Upward imports and private names imported from outside their package, one line each."""
    root = Path(root)
    bad = []
    for mod, path in project_modules(root).items():
        me = layer(mod)
        if me < 0:
            continue
        package = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
        for line, target, names in _imports(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            where = f"{path.relative_to(root)}:{line}"
            lt = layer(target)
            if lt > me:
                bad.append(f"{where} ({LAYER_NAMES[me]}) imports {target} ({LAYER_NAMES[lt]})")
            owner = _private_owner(target, names) if lt >= 0 else None
            if owner is not None and not (package == owner or package.startswith(owner + ".")):
                bad.append(f"{where} imports a private name of {owner}: {target} {names}")
    return bad
