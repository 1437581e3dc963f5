"""Synthetic benchmark sequences with exact ground truth (docs/design.md sections 4-5).

* :func:`generate_sequence` writes one of the six named sequences of the paper's Fig. 5
  (:data:`SEQUENCE_NAMES`) as a sequence folder, with procedural motion or a retargeted
  motion-capture clip; ``python -m mocap synth`` is its command line.
* :mod:`mocap.synth.motion` — procedural motion per sequence;
  :mod:`mocap.synth.retarget` — BVH / ASF-AMC clips onto our 23 parameters;
  :mod:`mocap.synth.actor` — the actor's proportions, mesh and appearance;
  :mod:`mocap.synth.shading` — smooth-shaded, textured rendering; :mod:`mocap.synth.scene` —
  the background; :mod:`mocap.synth.sensor` — camera effects;
  :mod:`mocap.synth.datasets` — the whole benchmark set and the bundled default sequence.
"""
from mocap.synth.sequence import (FPS, SEQUENCE_NAMES, SEQUENCES, SequenceSetup, SequenceSpec, generate_sequence,
                                  sequence_poses, setup_sequence)

__all__ = ["FPS", "SEQUENCES", "SEQUENCE_NAMES", "SequenceSetup", "SequenceSpec", "generate_sequence",
           "sequence_poses", "setup_sequence"]
