"""Exemplar pose proposals: the nearest of the toolkit's own renders of motion capture.

After Shakhnarovich, Viola & Darrell (ICCV 2003) and Agarwal & Triggs (PAMI 2006): a database
of exemplars, each a posture of the CMU motion capture trials (and its mirror image) seen from
a random heading, rendered as a class-label image and described by
:func:`mocap.imaging.descriptor.silhouette_descriptor`, reduced by a PCA. A frame's label
image is described the same way; the exemplars nearest to it (scikit-learn's
:class:`~sklearn.neighbors.NearestNeighbors`, built at load) and each one's 180-degree turn
(:func:`mocap.body.jumps.turned_mirror`: the silhouette hardly tells front from back) are the
proposals, at the leading hypothesis's depth and moved sideways and up or down so that their
silhouette sits on the frame's foreground
(:func:`mocap.track.proposals.place_by_silhouette`; a turn keeps its exemplar's root).

The database is built by ``python -m experiments.fit_proposer`` and shipped as
``mocap/track/exemplars.npz`` (float16 arrays, the data's attribution, a SHA-256 checksum of
the arrays that loading checks).
"""
from __future__ import annotations

import hashlib
import io
import json
import zipfile
import zlib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from mocap.body.jumps import turned_mirror
from mocap.body.pose import JOINT_LIMITS, N_PARAMETERS, PARAMETER_INDEX
from mocap.imaging.descriptor import DESCRIPTOR_GRID, descriptor_size, silhouette_descriptor
from mocap.imaging.prepare import PreparedFrame

__all__ = ["EXEMPLAR_FILE", "EXEMPLAR_FORMAT", "ExemplarSource", "exemplar_checksum"]

#: File name of the shipped database inside the package.
EXEMPLAR_FILE = "exemplars.npz"
#: Format tag of the file.
EXEMPLAR_FORMAT = "mocap-exemplars-1"
#: Nearest exemplars taken per frame by default (each with its turn: twice as many proposals).
DEFAULT_NEIGHBOURS = 10
#: The arrays of the file, in checksum order.
_ARRAYS = ("poses", "mean", "components", "projected")


def exemplar_checksum(arrays: dict) -> str:
    """SHA-256 (hex) of the database's arrays: name, dtype, shape and bytes of each in turn.

    Parameters
    ----------
    arrays : dict of str to ndarray
        ``poses``, ``mean``, ``components``, ``projected`` (as stored: float16).
    """
    h = hashlib.sha256()
    for name in _ARRAYS:
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


@dataclass(frozen=True, eq=False)
class ExemplarSource:
    """Proposal source of the exemplars nearest to a frame's silhouette (origin ``"exemplar"``).

    Attributes
    ----------
    poses : ndarray of float16, shape (n, 23)
        The exemplars' poses as rendered (metres, radians; the root as placed for rendering).
    mean : ndarray of float16, shape (D,)
        The PCA's mean descriptor (D = :func:`~mocap.imaging.descriptor.descriptor_size`).
    components : ndarray of float16, shape (c, D)
        The PCA's unit axes.
    projected : ndarray of float16, shape (n, c)
        Each exemplar's descriptor in the PCA's coordinates.
    attribution : str
        Where the training data came from (the data's licence asks for it).
    provenance : dict
        How the database was built (JSON-ready).
    neighbours : int
        Nearest exemplars taken per frame (each also turned: up to twice as many proposals).
    """

    poses: np.ndarray
    mean: np.ndarray
    components: np.ndarray
    projected: np.ndarray
    attribution: str = ""
    provenance: dict = field(default_factory=dict)
    neighbours: int = DEFAULT_NEIGHBOURS
    origin: str = "exemplar"

    def __post_init__(self) -> None:
        arrays = {name: np.ascontiguousarray(getattr(self, name), dtype=np.float16) for name in _ARRAYS}
        n, c, d = arrays["projected"].shape[0], arrays["components"].shape[0], descriptor_size(DESCRIPTOR_GRID)
        shapes = {"poses": (n, N_PARAMETERS), "mean": (d,), "components": (c, d), "projected": (n, c)}
        for name, shape in shapes.items():
            if arrays[name].shape != shape:
                raise ValueError(f"exemplar array {name!r} must have shape {shape}, got {arrays[name].shape}")
            if not np.isfinite(arrays[name]).all():
                raise ValueError(f"exemplar array {name!r} must be finite")
        if isinstance(self.neighbours, bool) or not isinstance(self.neighbours, (int, np.integer)) \
                or not 1 <= self.neighbours <= n:
            raise ValueError(f"neighbours must be an integer in [1, {n}], got {self.neighbours!r}")
        for name, value in arrays.items():
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        try:
            from sklearn.neighbors import NearestNeighbors
            from threadpoolctl import ThreadpoolController
        except ImportError as error:
            raise ImportError("the exemplar proposal source needs scikit-learn: pip install 'mocap[fit]'") from error

        object.__setattr__(self, "_mean", arrays["mean"].astype(np.float32))
        object.__setattr__(self, "_axes", np.ascontiguousarray(arrays["components"].astype(np.float32).T))
        object.__setattr__(self, "_index", NearestNeighbors(algorithm="brute").fit(
            arrays["projected"].astype(np.float32)))
        # one thread: scikit-learn's brute-force search runs on OpenMP threads, which spin-wait on a
        # busy machine (a query took 0.25-0.4 s instead of milliseconds with the other core loaded);
        # the controller is made once (threadpool_limits() looks for the libraries at every call)
        object.__setattr__(self, "_threads", ThreadpoolController())

    @classmethod
    def from_descriptors(cls, poses, descriptors, mean, components, attribution: str = "",
                         provenance: dict | None = None) -> "ExemplarSource":
        """A source of exemplars and their descriptors under a PCA.

        Parameters
        ----------
        poses : array_like, shape (n, 23)
            Metres and radians (stored as float16).
        descriptors : array_like, shape (n, D)
        mean : array_like, shape (D,)
        components : array_like, shape (c, D)
            The PCA's mean and axes (stored as float16); the descriptors are projected with the
            stored values, as a query is.
        attribution : str
        provenance : dict, optional
        """
        mean16 = np.asarray(mean, dtype=np.float16)
        axes16 = np.asarray(components, dtype=np.float16)
        projected = (np.asarray(descriptors, dtype=np.float32) - mean16.astype(np.float32)) @ axes16.astype(np.float32).T
        return cls(np.asarray(poses, dtype=np.float16), mean16, axes16, projected.astype(np.float16), attribution,
                   dict(provenance or {}))

    @property
    def checksum(self) -> str:
        """:func:`exemplar_checksum` of the arrays."""
        return exemplar_checksum({name: getattr(self, name) for name in _ARRAYS})

    @property
    def n_exemplars(self) -> int:
        return int(self.poses.shape[0])

    def with_neighbours(self, neighbours: int) -> "ExemplarSource":
        """The same database taking ``neighbours`` nearest exemplars per frame."""
        return ExemplarSource(self.poses, self.mean, self.components, self.projected, self.attribution,
                              self.provenance, neighbours)

    def describe(self, labels: np.ndarray, class_names: tuple[str, ...]) -> np.ndarray:
        """A label image's descriptor in the PCA's coordinates, shape (c,), float32."""
        d = silhouette_descriptor(labels, class_names, DESCRIPTOR_GRID)
        return (d - self._mean) @ self._axes

    def nearest(self, labels: np.ndarray, class_names: tuple[str, ...], k: int | None = None) -> np.ndarray:
        """Rows of the ``k`` exemplars nearest to a label image, nearest first.

        Parameters
        ----------
        labels : ndarray of uint8, shape (H, W)
        class_names : tuple of str
        k : int, optional
            Default :attr:`neighbours`.

        Returns
        -------
        ndarray of int64, shape (k,)
        """
        k = self.neighbours if k is None else int(k)
        query = self.describe(labels, class_names)[None]
        with self._threads.limit(limits=1, user_api="openmp"):     # the controller found at load
            _, rows = self._index.kneighbors(query, n_neighbors=k)
        return rows[0]

    def propose(self, prepared: PreparedFrame, context) -> list:
        """Proposals of one frame: the nearest exemplars, each followed by its turn.

        Parameters
        ----------
        prepared : PreparedFrame
        context : mocap.track.proposals.ProposalContext
            Its model (class names, skeleton), camera and leading pose (whose root depth the
            proposals take).

        Returns
        -------
        list of Proposal
            Up to ``2 * neighbours`` poses (23,) within the joint limits, root placed on the
            foreground; none for an empty frame.
        """
        from mocap.track.proposals import Proposal, place_by_silhouette

        if prepared.is_empty:
            return []
        yaw, z = PARAMETER_INDEX["chest_yaw"], PARAMETER_INDEX["root_z"]
        leader = np.asarray(context.leader, dtype=np.float64)
        out = []
        for row in self.nearest(prepared.labels, context.model.class_names):
            pose = self.poses[row].astype(np.float64)
            pose[z] = leader[z]
            # the heading nearest the leader's (the tracker's chest yaw runs over several turns)
            pose[yaw] = leader[yaw] + (pose[yaw] - leader[yaw] + np.pi) % (2.0 * np.pi) - np.pi
            placed = place_by_silhouette(np.clip(pose, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]), prepared.foreground,
                                         context.model, context.camera)
            # the turn keeps the root and (but for perspective) the silhouette: no placement of its own
            out += [Proposal(placed, self.origin), Proposal(turned_mirror(placed), self.origin)]
        return out

    def save(self, path: str | Path) -> str:
        """Write the database (compressed ``.npz``, atomically); returns its checksum."""
        from mocap.io.files import write_bytes_atomic

        meta = {"format": EXEMPLAR_FORMAT, "attribution": self.attribution, "provenance": self.provenance,
                "sha256": self.checksum}
        buffer = io.BytesIO()
        np.savez_compressed(buffer, meta=np.array(json.dumps(meta, sort_keys=True)),
                            **{name: getattr(self, name) for name in _ARRAYS})
        write_bytes_atomic(Path(path), buffer.getvalue())
        return self.checksum

    @classmethod
    def load(cls, path_or_file) -> "ExemplarSource":
        """Read a database file (a path or an open binary file).

        Raises
        ------
        ValueError
            If it is not a database file, or it is damaged (its checksum does not match).
        """
        try:
            with np.load(path_or_file, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                arrays = {name: z[name] for name in _ARRAYS}
        except FileNotFoundError:
            raise
        except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as error:
            raise ValueError(f"not a readable exemplar database ({error}): rebuild it with "
                             f"python -m experiments.fit_proposer") from None
        if not isinstance(meta, dict) or meta.get("format") != EXEMPLAR_FORMAT:
            raise ValueError(f"not an exemplar database (format {EXEMPLAR_FORMAT!r} expected)")
        if exemplar_checksum(arrays) != meta.get("sha256"):
            raise ValueError("exemplar database is damaged: its checksum does not match its arrays; rebuild it "
                             "with python -m experiments.fit_proposer")
        return cls(**arrays, attribution=str(meta.get("attribution", "")), provenance=dict(meta.get("provenance", {})))

    @classmethod
    def default(cls) -> "ExemplarSource":
        """The database shipped with the package (built from CMU motion capture; see the module)."""
        with resources.files("mocap.track").joinpath(EXEMPLAR_FILE).open("rb") as f:
            return cls.load(io.BytesIO(f.read()))
