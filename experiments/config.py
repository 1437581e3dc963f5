"""What a sweep runs: :class:`SweepConfig` (JSON, unknown keys rejected) and its presets.

Budgets are cost evaluations per frame (the paper's "iterations"). The grid of the paper's
Figs. 9-12 is ``region_budgets`` x ``edge_budgets``; the other runs feed Figs. 4, 6 and 8,
Table 1 and the split-policy comparison. Failure thresholds are analysis settings (stored
residuals are compared against them when figures are drawn), so changing them needs no rerun.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from types import MappingProxyType

from mocap.config import JsonConfig
from mocap.synth import SEQUENCE_NAMES

#: The paper's Table 2 resolutions (width, height), pixels.
TABLE2_SIZES: tuple[tuple[int, int], ...] = ((160, 120), (256, 256), (320, 240), (480, 480), (512, 512), (640, 480))
#: The paper's Table 1 totals (evaluations per frame, split 50/50).
TABLE1_TOTALS: tuple[int, ...] = (40, 100, 200, 300, 400, 500)
#: Split policies compared beyond the paper: its ``auto`` policy, 50/50, all-region, all-edge.
POLICIES: tuple[str, ...] = ("auto", "1:1", "1:0", "0:1")
#: Human names of :data:`POLICIES`.
POLICY_LABELS = MappingProxyType({"auto": "auto (paper)", "1:1": "50/50", "1:0": "all region", "0:1": "all edge"})
PRESETS: tuple[str, ...] = ("full", "quick")


def sequence_list(text: str) -> tuple[str, ...]:
    """The synthetic sequences a comma-separated ``--sequences`` names, in its order.

    Raises
    ------
    ValueError
        None named, or a name not of :data:`mocap.synth.SEQUENCE_NAMES` (one line naming them).
    """
    names = tuple(s.strip() for s in text.split(",") if s.strip())
    unknown = [s for s in names if s not in SEQUENCE_NAMES]
    if unknown or not names:
        raise ValueError(f"unknown sequence(s) {unknown}; choose from {', '.join(SEQUENCE_NAMES)}")
    return names


def _int_tuple(name: str, values, *, minimum: int = 0, allow_empty: bool = False) -> tuple[int, ...]:
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise ValueError(f"{name} must be a list of integers, got {values!r}")
    out = tuple(values)
    if not out and not allow_empty:
        raise ValueError(f"{name} must not be empty")
    for v in out:
        if isinstance(v, bool) or not isinstance(v, int) or v < minimum:
            raise ValueError(f"{name} must hold integers >= {minimum}, got {v!r}")
    if len(set(out)) != len(out):
        raise ValueError(f"{name} has repeated values: {out}")
    return tuple(sorted(out))


def _positive(name: str, value, *, integer: bool = False, allow_zero: bool = False) -> None:
    ok_type = isinstance(value, int) if integer else isinstance(value, (int, float))
    if isinstance(value, bool) or not ok_type or not math.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        kind = "integer" if integer else "number"
        raise ValueError(f"{name} must be a {'non-negative' if allow_zero else 'positive'} {kind}, got {value!r}")


@dataclass(frozen=True)
class SweepConfig(JsonConfig):
    """Settings of one sweep (saved as ``sweep.json`` in the results folder).

    Attributes
    ----------
    sequences : tuple of str
        Named synthetic sequences (:data:`mocap.synth.SEQUENCE_NAMES`).
    frames : int
        Frames per sequence (from the start of each).
    seed : int
        Data seed of :func:`mocap.synth.generate_sequence`.
    size : (int, int)
        Frame width and height, pixels.
    region_budgets, edge_budgets : tuple of int
        Evaluations per frame of the region and the edge step: the grid of Figs. 9-12.
    ftol : float
        Convergence test of both steps in the budget runs (relative simplex spread).
    converged_budget : int
        Per-step budget of the "converged" runs (Figs. 4, 6).
    converged_ftol : float
        Convergence test of the converged runs.
    limited_budget : int
        Per-step budget of the limited runs of Fig. 4 (the paper's 30 iterations).
    handoff_total : int
        Total evaluations per frame of Fig. 8.
    handoff_edge_budgets : tuple of int
        Edge-step budgets of Fig. 8 (the rest goes to the region step); at most ``handoff_total``.
    policies : tuple of str
        Split policies compared (``auto`` or ``R:E``).
    policy_totals : tuple of int
        Totals per frame at which the policies are compared.
    timing_sequences : tuple of str
        Sequences of the Table 1 timing runs (run alone, one at a time).
    table1_totals : tuple of int
        Totals of Table 1 (split 50/50).
    table2_sizes : tuple of (int, int)
        Resolutions of Table 2.
    table2_frames : int
        Frames generated per resolution for Table 2.
    table2_min_runs : int
        Timed calls per stage and resolution (at least).
    table2_min_seconds : float
        Seconds per stage and resolution (at least).
    motion_actors : tuple of str
        Named sequences whose actor (body, clothes, scene) is driven by each motion-capture
        clip given with ``--motion-dir``.
    motion_frames : int
        Frames per clip-driven sequence (at most; shorter clips are used whole).
    motion_budgets : tuple of int
        Budgets (both axes) of the grid run on clip-driven sequences.
    figure_sequence : str
        Sequence of the single-sequence figures (the paper shows its sequence 2).
    figure_failure_f : float
        A frame with F above this is a failure of F in the figures (Fig. 11; not the tracker's own
        failure mark, :data:`mocap.track.config.REGION_FAILURE_THRESHOLD`).
    figure_failure_edge_px : float, pixels
        A frame with mean edge distance above this is a failure of the edge distance (Fig. 12).
    mpjpe_failure_mm : float, millimetres
        A frame with MPJPE above this is a ground-truth failure.
    gradient : bool
        Also run the grid of Figs. 9-12 and Fig. 4's two-step runs with the gradient step on
        (:attr:`mocap.track.TrackerConfig.gradient_step`, taking
        :func:`mocap.track.config.gradient_budget` of each edge budget, so each total is
        unchanged); the figures then draw both. Off: the paper's simplex-only sweep.
    """

    sequences: tuple[str, ...] = SEQUENCE_NAMES
    frames: int = 150
    seed: int = 0
    size: tuple[int, int] = (160, 120)
    region_budgets: tuple[int, ...] = (0, 25, 50, 100, 150, 200, 300, 400, 500)
    edge_budgets: tuple[int, ...] = (0, 25, 50, 100, 150, 200, 300, 400, 500)
    ftol: float = 1e-3
    converged_budget: int = 3000
    converged_ftol: float = 1e-6
    limited_budget: int = 30
    handoff_total: int = 500
    handoff_edge_budgets: tuple[int, ...] = (0, 50, 100, 150, 200, 250, 300, 350, 400, 450, 500)
    policies: tuple[str, ...] = POLICIES
    policy_totals: tuple[int, ...] = (40, 100, 150, 200, 300, 400, 500)
    timing_sequences: tuple[str, ...] = SEQUENCE_NAMES
    table1_totals: tuple[int, ...] = TABLE1_TOTALS
    table2_sizes: tuple[tuple[int, int], ...] = TABLE2_SIZES
    table2_frames: int = 3
    table2_min_runs: int = 50
    table2_min_seconds: float = 0.5
    motion_actors: tuple[str, ...] = ("gestures-1", "gestures-2")
    motion_frames: int = 150
    motion_budgets: tuple[int, ...] = (0, 50, 100, 200, 300, 500)
    figure_sequence: str = "gestures-2"
    figure_failure_f: float = 0.3
    figure_failure_edge_px: float = 1.0
    mpjpe_failure_mm: float = 100.0
    gradient: bool = False

    def __post_init__(self) -> None:
        from mocap.track import split_budget

        for name in ("sequences", "timing_sequences", "motion_actors"):
            seqs = getattr(self, name)
            if isinstance(seqs, str) or not hasattr(seqs, "__iter__"):
                raise ValueError(f"{name} must be a list of sequence names, got {seqs!r}")
            object.__setattr__(self, name, tuple(seqs))
            for s in getattr(self, name):
                if s not in SEQUENCE_NAMES:
                    raise ValueError(f"{name}: unknown sequence {s!r}; choose from {', '.join(SEQUENCE_NAMES)}")
        if not self.sequences:
            raise ValueError("sequences must not be empty")
        if self.figure_sequence not in self.sequences:
            raise ValueError(f"figure_sequence {self.figure_sequence!r} must be one of sequences {self.sequences}")
        for name in ("frames", "motion_frames", "converged_budget", "limited_budget", "handoff_total",
                     "table2_frames", "table2_min_runs"):
            _positive(name, getattr(self, name), integer=True)
        _positive("seed", self.seed, integer=True, allow_zero=True)
        for name in ("ftol", "converged_ftol"):
            _positive(name, getattr(self, name), allow_zero=True)
        for name in ("table2_min_seconds", "figure_failure_f", "figure_failure_edge_px",
                     "mpjpe_failure_mm"):
            _positive(name, getattr(self, name))
        object.__setattr__(self, "size", _size("size", self.size))
        for name in ("region_budgets", "edge_budgets", "handoff_edge_budgets", "motion_budgets"):
            object.__setattr__(self, name, _int_tuple(name, getattr(self, name)))
        for name in ("policy_totals", "table1_totals"):
            object.__setattr__(self, name, _int_tuple(name, getattr(self, name), minimum=1))
        if max(self.handoff_edge_budgets) > self.handoff_total:
            raise ValueError(f"handoff_edge_budgets must not exceed handoff_total={self.handoff_total}")
        if not isinstance(self.gradient, bool):
            raise ValueError(f"gradient must be true or false, got {self.gradient!r}")
        if isinstance(self.policies, str) or not self.policies:
            raise ValueError(f"policies must be a non-empty list of split policies, got {self.policies!r}")
        object.__setattr__(self, "policies", tuple(self.policies))
        for p in self.policies:
            split_budget(100, p)                    # raises ValueError on a bad policy
        sizes = self.table2_sizes
        if isinstance(sizes, (str, bytes)) or not hasattr(sizes, "__iter__") or not tuple(sizes):
            raise ValueError(f"table2_sizes must be a non-empty list of [width, height], got {sizes!r}")
        object.__setattr__(self, "table2_sizes", tuple(_size("table2_sizes", s) for s in sizes))

    @classmethod
    def preset(cls, name: str) -> "SweepConfig":
        """The ``full`` (default) or ``quick`` preset.

        ``quick``: grid {0, 100, 250}^2 on two sequences of 40 frames with reduced
        Fig. 4/6/8, policy and timing runs (a few minutes on two cores).
        """
        if name == "full":
            return cls()
        if name == "quick":
            return cls(sequences=("gestures-2", "turning"), frames=40, region_budgets=(0, 100, 250),
                       edge_budgets=(0, 100, 250), converged_budget=1000, handoff_total=250,
                       handoff_edge_budgets=(0, 125, 250), policy_totals=(40, 200, 500),
                       timing_sequences=("gestures-2",), table2_frames=1, table2_min_runs=5,
                       table2_min_seconds=0.05, motion_frames=40, motion_budgets=(0, 250))
        raise ValueError(f"unknown preset {name!r}; choose from {', '.join(PRESETS)}")

    def with_changes(self, changes: dict) -> "SweepConfig":
        """A copy with some fields replaced (validated like the constructor)."""
        unknown = set(changes) - set(self.to_dict())
        if unknown:
            raise ValueError(f"unknown SweepConfig option(s): {', '.join(sorted(unknown))}")
        return replace(self, **changes)


def _size(name: str, size) -> tuple[int, int]:
    try:
        w, h = size
    except (TypeError, ValueError):
        raise ValueError(f"{name}: a size must be [width, height], got {size!r}") from None
    for v in (w, h):
        if isinstance(v, bool) or not isinstance(v, int) or not 16 <= v <= 4096:
            raise ValueError(f"{name}: width and height must be integers in [16, 4096], got {size!r}")
    return int(w), int(h)
