"""Slow, obviously-correct pure-NumPy twins of the compiled kernels.

Every ``@jit`` kernel in :mod:`mocap` is compared against its twin here in the tests.
Sections: rendering, costs, imaging.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from mocap.body.pose import PARAMETER_INDEX as P

# --- body ---


def naive_segment_transforms(pose, offsets):
    """Forward kinematics written from the documented conventions with scipy rotations.

    Returns a dict segment name -> (R (3, 3), t (3,)).
    """
    def rot(axes, angles):
        return Rotation.from_euler(axes, angles).as_matrix()  # intrinsic rotations, upper-case axes

    out = {}
    r_chest = rot("YXZ", [pose[P["chest_yaw"]], pose[P["chest_pitch"]], pose[P["chest_roll"]]])
    t_chest = np.asarray(pose[:3], float)
    out["chest"] = (r_chest, t_chest)
    r_head = r_chest @ rot("XZY", [pose[P["head_flex"]], pose[P["head_tilt"]], pose[P["head_turn"]]])
    out["head"] = (r_head, r_chest @ offsets[1] + t_chest)
    for side, seg, mirror in (("r", 2, 1.0), ("l", 5, -1.0)):
        g = lambda name: pose[P[f"{side}_{name}"]]
        r_ua = r_chest @ rot("XZY", [-g("shoulder_flex"), mirror * g("shoulder_abd"), mirror * g("shoulder_rot")])
        t_ua = r_chest @ offsets[seg] + t_chest
        r_fa = r_ua @ rot("XY", [-g("elbow_flex"), mirror * g("forearm_twist")])
        t_fa = r_ua @ offsets[seg + 1] + t_ua
        r_h = r_fa @ rot("XZ", [-g("wrist_flex"), mirror * g("wrist_dev")])
        t_h = r_fa @ offsets[seg + 2] + t_fa
        out[f"{side}_upper_arm"] = (r_ua, t_ua)
        out[f"{side}_forearm"] = (r_fa, t_fa)
        out[f"{side}_hand"] = (r_h, t_h)
    return out


# --- costs ---


def naive_non_overlapping_ratio(target, model, n_classes):
    """Eq. (1) with Python sets of pixel coordinates; empty unions drop out, all empty gives 1."""
    terms = []
    for c in range(1, n_classes + 1):
        a = set(zip(*np.nonzero(target == c)))
        b = set(zip(*np.nonzero(model == c)))
        union, inter = len(a | b), len(a & b)
        if union:
            terms.append((union - inter) / union)
    if not terms:
        return 1.0
    return float(np.prod(terms) ** (1.0 / len(terms)))


def naive_mean_edge_distance(distance, edges, penalty):
    """Eq. (2) by a plain loop."""
    values = [distance[i, j] for i in range(edges.shape[0]) for j in range(edges.shape[1]) if edges[i, j]]
    return float(sum(values) / len(values)) if values else float(penalty)


# --- imaging ---
