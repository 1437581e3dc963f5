"""The import layers of the package (docs/design.md section 1), as an AST check.

Layers, low to high; a module may import its own layer and below:

0 base    ``mocap/_*.py``, ``mocap/labels.py``, ``mocap/config.py``, ``mocap/io/atomic*``, ``jsonfile*``, ``files*``
1 body    ``mocap/body``
2 render  ``mocap/render``
3 image   ``mocap/imaging``, ``mocap/cost.py``, ``mocap/metrics.py``
4 fit     ``mocap/optimize.py``
5 track   ``mocap/track*``, ``mocap/calibrat*``, ``mocap/synth``, the rest of ``mocap/io``, ``mocap/pipeline.py``,
          ``mocap/bench.py`` (every other module of the package)
6 face    ``mocap/commands``, ``mocap/cli.py``, ``mocap/__main__.py``, ``experiments``, ``notebooks``, ``docs``

(The layers of ``../shared/tools/check_layers.py``.) A second rule: no module imports another
package's private names (``from mocap.x import _y``, ``import mocap.x._y``) — a private module
or name is used only inside the package that holds it.
"""
from __future__ import annotations

import ast
from pathlib import Path

LAYER_NAMES = ("base", "body", "render", "image", "fit", "track", "face")
_TOP = {"experiments", "notebooks", "docs"}
_BY_SUBPACKAGE = {"body": 1, "render": 2, "imaging": 3, "cost": 3, "metrics": 3, "optimize": 4,
                  "commands": 6, "cli": 6, "__main__": 6}


def layer(module: str) -> int:
    """Layer (0..6) of a dotted module name of the project; -1 for other packages."""
    parts = module.split(".")
    if parts[0] in _TOP:
        return 6
    if parts[0] != "mocap" or len(parts) == 1:
        return -1
    sub = parts[1]
    if (sub.startswith("_") and sub != "__main__") or sub in ("labels", "config") or (
            sub == "io" and len(parts) > 2 and parts[2].split("_")[0] in ("atomic", "jsonfile", "files")):
        return 0
    return _BY_SUBPACKAGE.get(sub, 5)


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
