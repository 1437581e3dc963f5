"""Acclaim skeleton (ASF) and motion (AMC) files, as the CMU database distributes them.

An ASF file describes bones (direction and length in the rest pose, a local axis frame
``axis`` with its Euler order, and rotational degrees of freedom) and their hierarchy; an AMC
file gives, per frame, the root translation and rotation and each bone's degrees of freedom
in degrees.

Conventions (those of the CMU viewers): a bone's local rotation relative to its parent, in
world rest axes, is ``C M C^-1`` where ``C`` is the ``axis`` rotation and ``M`` the rotation of
its degrees of freedom; both compose as rotations about fixed axes applied in the listed order
(``axis 0 0 20 XYZ`` is ``Rz(20) Ry(0) Rx(0)``, dof ``rx ry rz`` is ``Rz Ry Rx``). A bone starts
where its parent ends; the root has no length.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["Amc", "Asf", "AsfBone", "read_amc", "read_asf"]

_DOF_NAMES = ("rx", "ry", "rz", "tx", "ty", "tz", "l")


@dataclass(frozen=True)
class AsfBone:
    """One bone of an ASF skeleton.

    Attributes
    ----------
    name : str
    parent : int
        Index of the parent bone, -1 for the root.
    direction : ndarray, shape (3,)
        Unit direction in the rest pose (world axes).
    length : float
        File length units.
    axis : ndarray, shape (3,)
        Local frame angles, degrees.
    axis_order : str
        Order of ``axis`` (e.g. ``"XYZ"``).
    dofs : tuple of str
        Degrees of freedom in AMC order (``rx``, ``ry``, ``rz``; the root's are
        ``tx ty tz rx ry rz`` in its ``order``).
    """

    name: str
    parent: int
    direction: np.ndarray
    length: float
    axis: np.ndarray
    axis_order: str
    dofs: tuple[str, ...]

    def axis_matrix(self) -> np.ndarray:
        """The ``C`` rotation (3, 3) of the module docstring."""
        return Rotation.from_euler(self.axis_order.lower(), self.axis, degrees=True).as_matrix()


@dataclass(frozen=True)
class Asf:
    """A parsed ASF skeleton: bones with the root first, parents before children."""

    bones: tuple[AsfBone, ...]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.bones)

    @property
    def parents(self) -> np.ndarray:
        return np.array([b.parent for b in self.bones], dtype=np.int64)

    def offsets(self) -> np.ndarray:
        """Rest offset of each bone's start from its parent's start, (B, 3), file units."""
        out = np.zeros((len(self.bones), 3))
        for i, b in enumerate(self.bones):
            if b.parent >= 0:
                p = self.bones[b.parent]
                out[i] = p.direction * p.length
        return out


@dataclass(frozen=True)
class Amc:
    """Parsed AMC motion: per bone, per frame, its degrees of freedom (degrees / file units)."""

    asf: Asf
    values: dict[str, np.ndarray] = field(default_factory=dict)   # bone -> (N, len(dofs))
    n_frames: int = 0

    def root_positions(self) -> np.ndarray:
        """Root translation per frame, (N, 3), file units."""
        root = self.asf.bones[0]
        vals = self.values[root.name]
        return np.stack([vals[:, root.dofs.index(t)] for t in ("tx", "ty", "tz")], axis=1)

    def local_rotations(self) -> np.ndarray:
        """Rotation of every bone relative to its parent, world rest axes, (N, B, 3, 3)."""
        out = np.broadcast_to(np.eye(3), (self.n_frames, len(self.asf.bones), 3, 3)).copy()
        for i, bone in enumerate(self.asf.bones):
            rot = [k for k, d in enumerate(bone.dofs) if d.startswith("r")]
            if not rot or bone.name not in self.values:
                continue
            seq = "".join(bone.dofs[k][1] for k in rot)                 # fixed axes, in order
            m = Rotation.from_euler(seq, self.values[bone.name][:, rot], degrees=True).as_matrix()
            c = bone.axis_matrix()
            out[:, i] = c @ m @ c.T
        return out


def _sections(text: str) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    current = None
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if line.startswith(":"):
            key, _, rest = line[1:].partition(" ")
            current = key.lower()
            out.setdefault(current, [])
            if rest.strip():
                out[current].append(rest.strip())
        elif current is not None:
            out[current].append(line)
    return out


def read_asf(path: str | Path) -> Asf:
    """Read an ASF skeleton.

    Raises
    ------
    FileNotFoundError
    ValueError
        With the file name on malformed content (missing root, bonedata or hierarchy, a bone
        of unknown parent, unknown degrees of freedom).
    """
    path = Path(path)
    sec = _sections(path.read_text(encoding="utf-8", errors="replace"))
    for key in ("root", "bonedata", "hierarchy"):
        if key not in sec:
            raise ValueError(f"{path}: not an ASF skeleton (no :{key} section)")
    root = {ln.split()[0].lower(): ln.split()[1:] for ln in sec["root"]}
    try:
        root_order = tuple(t.lower() for t in root["order"])
        root_axis = root["axis"][0].upper()
        root_orient = np.array([float(v) for v in root.get("orientation", ["0", "0", "0"])])
    except (KeyError, IndexError, ValueError):
        raise ValueError(f"{path}: bad :root section (needs order, axis, orientation)") from None
    raw: dict[str, dict] = {}
    bone: dict | None = None
    lines = sec["bonedata"]
    i = 0
    while i < len(lines):
        words = lines[i].split()
        key = words[0].lower()
        if key == "begin":
            bone = {"dof": (), "axis": (np.zeros(3), "XYZ")}
        elif key == "end":
            if bone is None or "name" not in bone:
                raise ValueError(f"{path}: a bone without a name")
            raw[bone["name"]] = bone
            bone = None
        elif bone is not None:
            try:
                if key == "name":
                    bone["name"] = words[1]
                elif key == "direction":
                    bone["direction"] = np.array([float(v) for v in words[1:4]])
                elif key == "length":
                    bone["length"] = float(words[1])
                elif key == "axis":
                    bone["axis"] = (np.array([float(v) for v in words[1:4]]), words[4].upper())
                elif key == "dof":
                    dofs = tuple(w.lower() for w in words[1:])
                    if any(d not in _DOF_NAMES for d in dofs):
                        raise ValueError(f"{path}: unknown degree of freedom in {' '.join(dofs)}")
                    bone["dof"] = dofs
            except (IndexError, ValueError) as exc:
                raise ValueError(f"{path}: bad bone entry {lines[i]!r} ({exc})") from None
        i += 1
    parent_of: dict[str, str] = {}
    for ln in sec["hierarchy"]:
        words = ln.split()
        if words[0].lower() in ("begin", "end"):
            continue
        for child in words[1:]:
            parent_of[child] = words[0]
    order = ["root"]
    k = 0
    while k < len(order):
        order += [c for c, p in parent_of.items() if p == order[k]]
        k += 1
    missing = [n for n in parent_of if n not in raw and n != "root"]
    if missing:
        raise ValueError(f"{path}: hierarchy names bones without bonedata: {', '.join(missing)}")
    bones = [AsfBone("root", -1, np.zeros(3), 0.0, root_orient, root_axis, root_order)]
    for name in order[1:]:
        b = raw[name]
        if "direction" not in b or "length" not in b:
            raise ValueError(f"{path}: bone {name!r} lacks a direction or length")
        d = b["direction"]
        norm = np.linalg.norm(d)
        bones.append(AsfBone(name, order.index(parent_of[name]), d / norm if norm > 0 else d, b["length"],
                             b["axis"][0], b["axis"][1], b["dof"]))
    return Asf(tuple(bones))


def read_amc(path: str | Path, asf: Asf) -> Amc:
    """Read an AMC motion for the skeleton ``asf``.

    Raises
    ------
    FileNotFoundError
    ValueError
        With the file name on a bone unknown to the skeleton, a wrong value count, or no
        frames.
    """
    path = Path(path)
    index = {b.name: b for b in asf.bones}
    frames: list[dict[str, list[float]]] = []
    for raw in path.read_text(encoding="utf-8", errors="replace").splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line or line.startswith(":"):
            continue
        words = line.split()
        if len(words) == 1 and words[0].isdigit():
            frames.append({})
            continue
        if not frames:
            raise ValueError(f"{path}: values before the first frame number")
        name = words[0]
        if name not in index:
            raise ValueError(f"{path}: bone {name!r} is not in the skeleton")
        try:
            vals = [float(v) for v in words[1:]]
        except ValueError:
            raise ValueError(f"{path}: a value of {name!r} is not a number") from None
        if len(vals) != len(index[name].dofs):
            raise ValueError(f"{path}: bone {name!r} has {len(vals)} values for {len(index[name].dofs)} dofs")
        frames[-1][name] = vals
    if not frames:
        raise ValueError(f"{path}: no frames")
    values = {}
    for b in asf.bones:
        if b.dofs:
            values[b.name] = np.array([f.get(b.name, [0.0] * len(b.dofs)) for f in frames], dtype=np.float64)
    return Amc(asf, values, len(frames))
