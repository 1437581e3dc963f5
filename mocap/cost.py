"""Matching costs between a rendered pose and a prepared video frame.

- :class:`RegionCost`: the non-overlapping ratio F(q) of the paper's eq. (1) between the
  model's coloured silhouette and the segmented label image, over m colour classes.
- :class:`EdgeCost`: the mean edge distance D_c of eq. (2): the mean, over the model's
  occluding-edge pixels, of the image's distance-to-nearest-edge map.
- :class:`KeypointCost`: beyond the paper, the keypoint distance D_k: the weighted mean, over
  the joints a 2D detector found, of a robust distance (:func:`robust_distance`, pixels) between
  the model's projected joint and the keypoint, each joint weighted by its confidence and by
  whether it lies on the person's silhouette (:func:`keypoint_gates`), the robust scale from
  the detector's measured noise (:func:`keypoint_scales`); optionally the lower of the
  detector's labelling and the left/right swapped one (``swap``).

Each is built once per frame from its target and called as ``cost(pose) -> float``. One call
is one compiled function that poses the mesh, rasterizes it and accumulates the cost only
inside the model's bounding box, then clears what it drew; there is no Python work per pixel.
The cost objects hold scratch buffers, so one object must not be called from two threads at
once: :meth:`~RegionCost.spare` gives another thread a twin with buffers of its own.

Degenerate cases (documented, finite, never NaN):
- F: a class whose union ``|A_c ∪ B_c|`` is empty (neither image nor model has it) drops out
  of the product and of the exponent (m counts the remaining classes); if every class is empty,
  F = 1 (:data:`EMPTY_REGION_COST`).
- D_c: when the model has no occluding-edge pixel in view, D_c is the ``no_edge_penalty``
  (default: the distance map's truncation value, i.e. its maximum).
- D_k: a joint nearer than the near plane counts the image's diagonal as its distance (through
  the robust distance); with no keypoint present D_k is 0 (no evidence).

Gradients (the paper's future work, issue 30): :meth:`EdgeCost.gradient` and
:meth:`RegionCost.gradient` differentiate eq. (2) and eq. (1) with respect to the 23 pose
parameters from one render each (see :class:`EdgeGradient` and :class:`RegionGradient`).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from mocap._numba import jit
from mocap.body.kinematics import (PARAMETER_MOVES, parameter_axes_into, point_jacobian_into,
                                   segment_transforms_into)
from mocap.body.mesh import edge_faces
from mocap.body.model import BodyModel
from mocap.body.pose import N_PARAMETERS, check_pose
from mocap.body.skeleton import JOINT_NAMES, SEGMENT_NAMES
from mocap.io.keypoints import SWAPPED_JOINTS
from mocap.labels import MAX_CLASSES, UNKNOWN
from mocap.render.camera import Camera
from mocap.render.rasterize import (EDGE_DEPTH_GAP_M, Buffers, Scene, check_edge_gap, occluding_edge_marks_into,
                                    occluding_edge_sum_and_clear, render_scene_into)

#: F when neither the image nor the model has a pixel of any class.
EMPTY_REGION_COST = 1.0


class RegionKernelArgs(NamedTuple):
    """Second argument of :func:`region_cost_kernel` (:meth:`RegionCost.kernel_args`).

    Attributes
    ----------
    scene : Scene
    buffers : Buffers
    target : ndarray, shape (height * width,), uint8
        Flat label image.
    target_count : ndarray, shape (m + 1,), int64
        |A_c| per class c = 1..m (index 0 unused, 0).
    n_classes : int
        m.
    model_count, overlap_count : ndarray, shape (m + 1,), int64
        Scratch for |B_c| and |A_c ∩ B_c|.
    ignore_unknown : bool
    """

    scene: Scene
    buffers: Buffers
    target: np.ndarray
    target_count: np.ndarray
    n_classes: int
    model_count: np.ndarray
    overlap_count: np.ndarray
    ignore_unknown: bool


class EdgeKernelArgs(NamedTuple):
    """Second argument of :func:`edge_cost_kernel` (:meth:`EdgeCost.kernel_args`).

    Attributes
    ----------
    scene : Scene
    buffers : Buffers
    distance : ndarray, shape (height * width,), float32, pixels
        Flat distance-to-edge map.
    marks : ndarray, shape (height * width,), bool
        Scratch for the edge pixels found (all False between calls).
    edge_gap : float, metres
    no_edge_penalty : float, pixels
    """

    scene: Scene
    buffers: Buffers
    distance: np.ndarray
    marks: np.ndarray
    edge_gap: float
    no_edge_penalty: float


class EdgeGradientArgs(NamedTuple):
    """Second argument of :func:`edge_gradient_kernel` (:meth:`EdgeCost.gradient_args`).

    Attributes
    ----------
    cost : EdgeKernelArgs
    gradient_u, gradient_v : ndarray, shape (height * width,), float64, pixels per pixel
        Flat central-difference gradient of the distance map along u (columns) and v (rows).
    edges, edge_faces : ndarray, shape (E, 2), int64
        Mesh edges (vertex pairs) and the two triangles sharing each
        (:func:`~mocap.body.mesh.edge_faces`).
    moves : ndarray, shape (23, 8), bool
        :data:`~mocap.body.kinematics.PARAMETER_MOVES`.
    points : ndarray, shape (V, 3), float64
        Scratch: the posed vertices in camera coordinates, metres.
    facing : ndarray, shape (T,), int8
        Scratch: 1 front-facing, 0 back-facing, -1 not projectable (a vertex nearer than the near plane).
    axes, pivots : ndarray, shape (23, 3), float64
        Scratch (:func:`~mocap.body.kinematics.parameter_axes_into`).
    jacobian : ndarray, shape (3, 23), float64
        Scratch for one point's dX/dq.
    spacing : float, pixels
        Distance between contour samples along a projected contour edge (at most).
    """

    cost: EdgeKernelArgs
    gradient_u: np.ndarray
    gradient_v: np.ndarray
    edges: np.ndarray
    edge_faces: np.ndarray
    moves: np.ndarray
    points: np.ndarray
    facing: np.ndarray
    axes: np.ndarray
    pivots: np.ndarray
    jacobian: np.ndarray
    spacing: float


class RegionGradientArgs(NamedTuple):
    """Second argument of :func:`region_gradient_kernel` (:meth:`RegionCost.gradient_args`).

    Attributes
    ----------
    cost : RegionKernelArgs
    edges, edge_faces, moves, points, facing, axes, pivots, jacobian, spacing
        As in :class:`EdgeGradientArgs`.
    model_rate, overlap_rate : ndarray, shape (m + 1, 23), float64
        Scratch: d|B_c|/dq and d|A_c ∩ B_c|/dq, pixels per parameter unit.
    part_segment : ndarray, shape (P,), int64
        Segment carrying each part (index of the render's part buffer - 1).
    edge_gap : float, metres
        Depth step that makes a boundary between two parts an occluding contour
        (:data:`~mocap.render.rasterize.EDGE_DEPTH_GAP_M`); smaller steps are seams.
    jacobian_other : ndarray, shape (3, 23), float64
        Scratch.
    """

    cost: RegionKernelArgs
    edges: np.ndarray
    edge_faces: np.ndarray
    moves: np.ndarray
    points: np.ndarray
    facing: np.ndarray
    axes: np.ndarray
    pivots: np.ndarray
    jacobian: np.ndarray
    spacing: float
    model_rate: np.ndarray
    overlap_rate: np.ndarray
    part_segment: np.ndarray
    edge_gap: float
    jacobian_other: np.ndarray


class KeypointKernelArgs(NamedTuple):
    """Second argument of :func:`keypoint_cost_kernel` (:meth:`KeypointCost.kernel_args`).

    Attributes
    ----------
    offsets : ndarray, shape (8, 3), float64, metres
        Skeleton offsets.
    joint_segment : ndarray, shape (n,), int64
        Segment of each present keypoint's joint.
    joint_local : ndarray, shape (n, 3), float64, metres
        The joint in its segment's frame.
    uv : ndarray, shape (n, 2), float64, pixels
        The keypoints.
    weight : ndarray, shape (n,), float64
        Their confidences times their silhouette gates (:func:`keypoint_gates`), divided by
        those products' sum.
    camera : ndarray, shape (5,), float64
        :meth:`~mocap.render.camera.Camera.as_array`.
    transforms : ndarray, shape (8, 3, 4), float64
        Scratch for the segment transforms.
    behind_penalty : float, pixels
        Distance counted for a joint nearer than the near plane.
    scale : ndarray, shape (n,), float64, pixels
        Each keypoint's robust scale (:func:`robust_distance`; inf: the plain distance).
    swap : bool
        Also score the labelling with left and right swapped; the cost is the lower of the two.
    swapped_segment : ndarray, shape (n,), int64
        Segment of each keypoint's joint under the swapped labelling (its twin on the other side).
    swapped_local : ndarray, shape (n, 3), float64, metres
        That joint in its segment's frame.
    swapped_order : ndarray, shape (n,), int64
        The keypoints in the order of their twins' joints (:data:`~mocap.body.skeleton.JOINT_NAMES`
        order): the swapped labelling's sum runs in the model's joint order, as the detector's does,
        so that keypoints whose labels are the other way round give the same float bit for bit.
    """

    offsets: np.ndarray
    joint_segment: np.ndarray
    joint_local: np.ndarray
    uv: np.ndarray
    weight: np.ndarray
    camera: np.ndarray
    transforms: np.ndarray
    behind_penalty: float
    scale: np.ndarray
    swap: bool
    swapped_segment: np.ndarray
    swapped_local: np.ndarray
    swapped_order: np.ndarray


# ----------------------------------------------------------------------------- kernels
@jit
def _region_counts_and_clear(part_buf, depth_buf, part_label, width, bbox, target, n_classes,
                             model_count, overlap_count, ignore_unknown):
    """|B_c| and |A_c ∩ B_c| for c = 1..m (index c) over the model's box; clears the box.
    With ``ignore_unknown`` model pixels over UNKNOWN image pixels are not counted in B_c.

    Along a row the part changes rarely, so counts accumulate in registers over each run of
    one part and reach the count arrays only at the run's end (index 0 collects background).
    """
    for c in range(n_classes + 1):
        model_count[c] = 0
        overlap_count[c] = 0
    x0, x1 = bbox[0], bbox[2]
    # 8 pixels at a time where the width allows: all-background words are skipped (nothing
    # outside the box was drawn, so whole words never count a pixel twice or a stray one)
    use_words = width % 8 == 0
    words = part_buf[: part_buf.size - part_buf.size % 8].view(np.uint64)
    for py in range(bbox[1], bbox[3] + 1):
        row = py * width
        cur = np.uint8(0)
        c = 0
        run = 0
        hit = 0
        if use_words:
            k_from, k_to = (row + x0) // 8, (row + x1) // 8 + 1
        else:
            k_from, k_to = 0, 1
        for k in range(np.uint64(k_from), np.uint64(k_to)):
            if use_words:
                if words[k] == 0:
                    continue
                a, b = k * np.uint64(8), k * np.uint64(8) + np.uint64(8)
            else:
                a, b = np.uint64(row + x0), np.uint64(row + x1 + 1)
            for idx in range(a, b):
                p = part_buf[idx]
                if p != cur:
                    model_count[c] += run
                    overlap_count[c] += hit
                    cur = p
                    c = part_label[p - 1] if p != 0 else 0
                    run = 0
                    hit = 0
                t = target[idx]
                run += 1 - (ignore_unknown & (t == UNKNOWN))
                hit += t == c
        model_count[c] += run
        overlap_count[c] += hit
        part_buf[row + x0: row + x1 + 1] = 0
        depth_buf[row + x0: row + x1 + 1] = 0.0


@jit
def _non_overlapping_ratio(target_count, model_count, overlap_count, n_classes):
    """Eq. (1) from per-class counts (index 1..m), with the documented empty-union rule.

    A class matched pixel for pixel while another is not would make the product 0 whatever the
    others do (a small class such as hair often is, on clean frames): its term counts as
    ``1 / (union + 1)`` instead, below any real mismatch of that class. F is 0 only when every
    class matches."""
    log_sum = 0.0
    used = 0
    exact = 0
    for c in range(1, n_classes + 1):
        union = target_count[c] + model_count[c] - overlap_count[c]
        if union == 0:
            continue
        used += 1
        miss = union - overlap_count[c]
        if miss == 0:
            exact += 1
            log_sum += np.log(1.0 / (union + 1.0))
        else:
            log_sum += np.log(miss / union)
    if used == 0:
        return EMPTY_REGION_COST
    if exact == used:
        return 0.0
    return np.exp(log_sum / used)


@jit
def region_cost_kernel(pose, args):
    """Compiled F(pose) (eq. 1) for an unchecked float64 (23,) pose and a
    :class:`RegionKernelArgs`; leaves the buffers cleared."""
    scene, buffers = args.scene, args.buffers
    render_scene_into(pose, scene, buffers)
    _region_counts_and_clear(buffers.part_ids, buffers.inverse_depth, scene.part_label, scene.width, buffers.box,
                             args.target, args.n_classes, args.model_count, args.overlap_count, args.ignore_unknown)
    return _non_overlapping_ratio(args.target_count, args.model_count, args.overlap_count, args.n_classes)


@jit
def edge_cost_kernel(pose, args):
    """Compiled D_c(pose) (eq. 2), pixels, for an unchecked float64 (23,) pose and an
    :class:`EdgeKernelArgs`; leaves the buffers cleared."""
    render_scene_into(pose, args.scene, args.buffers)
    total, n = occluding_edge_sum_and_clear(args.scene, args.buffers, args.edge_gap, args.distance, args.marks)
    if n == 0:
        return args.no_edge_penalty
    return total / n


@jit
def _bilinear(image, width, height, u, v):
    """Bilinear interpolation of the flat ``image`` at pixel coordinates (u, v) (pixel centres at
    half-integers), clamped at the image border."""
    x, y = u - 0.5, v - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = x - x0, y - y0
    i0 = min(max(np.int64(x0), 0), width - 1)
    i1 = min(max(np.int64(x0) + 1, 0), width - 1)
    j0 = min(max(np.int64(y0), 0), height - 1)
    j1 = min(max(np.int64(y0) + 1, 0), height - 1)
    top = (1.0 - fx) * image[j0 * width + i0] + fx * image[j0 * width + i1]
    bottom = (1.0 - fx) * image[j1 * width + i0] + fx * image[j1 * width + i1]
    return (1.0 - fy) * top + fy * bottom


@jit
def _marked_near(marks, width, height, px, py):
    """Whether pixel (px, py) or one of its 4-neighbours is marked (False outside the image)."""
    if px < 0 or py < 0 or px >= width or py >= height:
        return False
    i = py * width + px
    if marks[i]:
        return True
    return ((px > 0 and marks[i - 1]) or (px + 1 < width and marks[i + 1]) or (py > 0 and marks[i - width])
            or (py + 1 < height and marks[i + width]))


@jit
def _pose_vertices(scene, transforms, points, facing, triangles):
    """Camera coordinates of every vertex into ``points`` and each triangle's facing into
    ``facing`` (1 front, 0 back, -1 a vertex nearer than the near plane), from the float projection."""
    cam, offsets = scene.camera, scene.vertices
    for i in range(offsets.shape[0]):
        s = scene.vertex_segment[i]
        for r in range(3):
            points[i, r] = (transforms[s, r, 0] * offsets[i, 0] + transforms[s, r, 1] * offsets[i, 1]
                            + transforms[s, r, 2] * offsets[i, 2] + transforms[s, r, 3])
    for t in range(triangles.shape[0]):
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        if points[a, 2] < cam[4] or points[b, 2] < cam[4] or points[c, 2] < cam[4]:
            facing[t] = -1
            continue
        ua, va = cam[0] * points[a, 0] / points[a, 2], cam[1] * points[a, 1] / points[a, 2]
        ub, vb = cam[0] * points[b, 0] / points[b, 2], cam[1] * points[b, 1] / points[b, 2]
        uc, vc = cam[0] * points[c, 0] / points[c, 2], cam[1] * points[c, 1] / points[c, 2]
        facing[t] = 1 if (ub - ua) * (vc - va) - (uc - ua) * (vb - va) < 0.0 else 0


@jit
def edge_gradient_kernel(pose, args, gradient):
    """Compiled gradient of eq. (2) for an unchecked float64 (23,) pose and an
    :class:`EdgeGradientArgs`, into ``gradient`` (23,); leaves the buffers cleared.

    Returns ``(D_c, contour mean, samples)``: eq. (2) from the render's edge pixels, pixels;
    the mean of the bilinearly interpolated distance over the visible contour samples (the
    smooth function whose gradient is written, pixels; the penalty with no sample); their number.
    """
    value, mean, _, samples = edge_normal_equations_kernel(pose, args, gradient, gradient[:0], args.jacobian[:0, :0])
    return value, mean, samples


@jit
def edge_normal_equations_kernel(pose, args, gradient, rhs, normal):
    """:func:`edge_gradient_kernel`, and, when ``rhs`` (23,) and ``normal`` (23, 23) are not
    empty, the Gauss–Newton normal equations of the contour's mean squared distance: with
    r_s the distance at sample s and J_s its gradient (per parameter), ``rhs`` = mean r_s J_s and
    ``normal`` = mean J_s^T J_s (zero without a sample).

    Returns ``(D_c, contour mean, contour mean square, samples)`` (pixels, pixels, pixels²).
    """
    c = args.cost
    scene, buffers = c.scene, c.buffers
    width, height, cam = scene.width, scene.height, scene.camera
    want_normal = normal.shape[0] > 0
    n_par = gradient.shape[0]
    render_scene_into(pose, scene, buffers)
    total, n = occluding_edge_marks_into(scene, buffers, c.edge_gap, c.distance, c.marks)
    value = c.no_edge_penalty if n == 0 else total / n
    transforms, points, jac = buffers.transforms, args.points, args.jacobian
    _pose_vertices(scene, transforms, points, args.facing, scene.triangles)
    parameter_axes_into(pose, transforms, args.axes, args.pivots)
    for k in range(n_par):
        gradient[k] = 0.0
        if want_normal:
            rhs[k] = 0.0
            for j in range(n_par):
                normal[k, j] = 0.0
    row = np.empty(n_par)
    sum_value = 0.0
    sum_square = 0.0
    samples = 0
    for e in range(args.edges.shape[0]):
        fa, fb = args.facing[args.edge_faces[e, 0]], args.facing[args.edge_faces[e, 1]]
        if fa < 0 or fb < 0 or fa == fb:
            continue                                   # not a contour generator
        a, b = args.edges[e, 0], args.edges[e, 1]
        seg = scene.vertex_segment[a]
        ua, va = cam[0] * points[a, 0] / points[a, 2] + cam[2], cam[1] * points[a, 1] / points[a, 2] + cam[3]
        ub, vb = cam[0] * points[b, 0] / points[b, 2] + cam[2], cam[1] * points[b, 1] / points[b, 2] + cam[3]
        n_s = max(np.int64(np.ceil(np.sqrt((ub - ua) ** 2 + (vb - va) ** 2) / args.spacing)), 1)
        for j in range(n_s):
            t = (j + 0.5) / n_s
            x = (1.0 - t) * points[a, 0] + t * points[b, 0]
            y = (1.0 - t) * points[a, 1] + t * points[b, 1]
            z = (1.0 - t) * points[a, 2] + t * points[b, 2]
            iz = 1.0 / z
            u, v = cam[0] * x * iz + cam[2], cam[1] * y * iz + cam[3]
            if not _marked_near(c.marks, width, height, np.int64(np.floor(u)), np.int64(np.floor(v))):
                continue                               # hidden, or not an occluding edge in the render
            samples += 1
            r = _bilinear(c.distance, width, height, u, v)
            sum_value += r
            sum_square += r * r
            gu = _bilinear(args.gradient_u, width, height, u, v)
            gv = _bilinear(args.gradient_v, width, height, u, v)
            # d(u, v)/dX of the pinhole projection, folded with the distance gradient
            wx, wy = gu * cam[0] * iz, gv * cam[1] * iz
            wz = -(wx * x + wy * y) * iz
            point_jacobian_into(x, y, z, seg, args.axes, args.pivots, args.moves, jac)
            for k in range(n_par):
                row[k] = wx * jac[0, k] + wy * jac[1, k] + wz * jac[2, k]
                gradient[k] += row[k]
            if want_normal:
                for k in range(n_par):
                    if row[k] != 0.0:
                        rhs[k] += r * row[k]
                        for i in range(k, n_par):
                            normal[k, i] += row[k] * row[i]
    box = buffers.box
    for py in range(box[1], box[3] + 1):
        c.marks[py * width + box[0]: py * width + box[2] + 1] = False
    if samples == 0:
        return value, c.no_edge_penalty, c.no_edge_penalty ** 2, 0
    for k in range(n_par):
        gradient[k] /= samples
        if want_normal:
            rhs[k] /= samples
            for i in range(k, n_par):
                normal[k, i] /= samples
                normal[i, k] = normal[k, i]
    return value, sum_value / samples, sum_square / samples, samples


@jit
def _label_share(target, width, height, u, v, label, count_unknown):
    """Bilinear share of the target pixels around (u, v) whose label is ``label`` (with
    ``count_unknown``: whose label is not UNKNOWN), pixel centres at half-integers, clamped."""
    x, y = u - 0.5, v - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = x - x0, y - y0
    share = 0.0
    for dj in range(2):
        j = min(max(np.int64(y0) + dj, 0), height - 1)
        wy = fy if dj == 1 else 1.0 - fy
        for di in range(2):
            i = min(max(np.int64(x0) + di, 0), width - 1)
            wx = fx if di == 1 else 1.0 - fx
            t = target[j * width + i]
            hit = (t != UNKNOWN) if count_unknown else (t == label)
            if hit:
                share += wx * wy
    return share


@jit
def _pixel_point(idx, width, depth_buf, cam):
    """Camera point (metres) of the surface seen at the centre of flat pixel ``idx``."""
    z = 1.0 / depth_buf[idx]
    u, v = idx % width + 0.5, idx // width + 0.5
    return z * (u - cam[2]) / cam[0], z * (v - cam[3]) / cam[1], z


@jit
def _seam_rates(scene, buffers, args, target, ignore_unknown):
    """Add to the class rates of :func:`region_gradient_kernel` the seams: boundaries between two
    parts of different classes with no occluding depth step (a part's cut such as face and hair,
    or where two parts meet), found between 4-neighbour pixels. Such a seam moves with both
    surfaces: its normal speed is that of the two pixels' surface points, averaged; one pixel of
    it moving by one pixel turns one pixel of area from one class to the other. Returns the
    seam pixel pairs counted."""
    part_buf, depth_buf = buffers.part_ids, buffers.inverse_depth
    width, height, cam = scene.width, scene.height, scene.camera
    box = buffers.box
    d_model, d_overlap = args.model_rate, args.overlap_rate
    jac, jac_b = args.jacobian, args.jacobian_other
    n_par = d_model.shape[1]
    count = 0
    for y in range(box[1], box[3] + 1):
        for x in range(box[0], box[2] + 1):
            a = y * width + x
            pa = part_buf[a]
            if pa == 0:
                continue
            for k2 in range(2):
                if k2 == 0:
                    if x + 1 > box[2]:
                        continue
                    b = a + 1
                    nu, nv = 1.0, 0.0
                else:
                    if y + 1 > box[3]:
                        continue
                    b = a + width
                    nu, nv = 0.0, 1.0
                pb = part_buf[b]
                if pb == 0 or pb == pa:
                    continue
                ca, cb = np.int64(scene.part_label[pa - 1]), np.int64(scene.part_label[pb - 1])
                if ca == cb:
                    continue
                za, zb = depth_buf[a], depth_buf[b]
                if abs(za - zb) > args.edge_gap * za * zb:
                    continue                           # an occluding contour: the mesh samples have it
                count += 1
                xa, ya, wa = _pixel_point(a, width, depth_buf, cam)
                xb, yb, wb = _pixel_point(b, width, depth_buf, cam)
                point_jacobian_into(xa, ya, wa, args.part_segment[pa - 1], args.axes, args.pivots, args.moves, jac)
                point_jacobian_into(xb, yb, wb, args.part_segment[pb - 1], args.axes, args.pivots, args.moves, jac_b)
                ua_x, ua_y, ua_z = nu * cam[0] / wa, nv * cam[1] / wa, -(nu * cam[0] * xa + nv * cam[1] * ya) / (wa * wa)
                ub_x, ub_y, ub_z = nu * cam[0] / wb, nv * cam[1] / wb, -(nu * cam[0] * xb + nv * cam[1] * yb) / (wb * wb)
                # target shares at the seam: the mean of the two pixels (bilinear at their midpoint)
                ta, tb = target[a], target[b]
                counted = 1.0 if not ignore_unknown else 0.5 * ((ta != UNKNOWN) + (tb != UNKNOWN))
                hit_a = 0.5 * ((ta == ca) + (tb == ca))
                hit_b = 0.5 * ((ta == cb) + (tb == cb))
                for k in range(n_par):
                    speed = 0.5 * (ua_x * jac[0, k] + ua_y * jac[1, k] + ua_z * jac[2, k]
                                   + ub_x * jac_b[0, k] + ub_y * jac_b[1, k] + ub_z * jac_b[2, k])
                    d_model[ca, k] += counted * speed
                    d_overlap[ca, k] += hit_a * speed
                    d_model[cb, k] -= counted * speed
                    d_overlap[cb, k] -= hit_b * speed
    return count


@jit
def region_gradient_kernel(pose, args, gradient):
    """Compiled gradient of eq. (1) for an unchecked float64 (23,) pose and a
    :class:`RegionGradientArgs`, into ``gradient`` (23,); leaves the buffers cleared.

    Returns ``(F, boundary samples)``. See :class:`RegionGradient` for the method.
    """
    c = args.cost
    scene, buffers = c.scene, c.buffers
    width, height, cam = scene.width, scene.height, scene.camera
    part_buf, depth_buf = buffers.part_ids, buffers.inverse_depth
    n_par = gradient.shape[0]
    d_model, d_overlap = args.model_rate, args.overlap_rate
    d_model[:, :] = 0.0
    d_overlap[:, :] = 0.0
    render_scene_into(pose, scene, buffers)
    transforms, points, jac = buffers.transforms, args.points, args.jacobian
    _pose_vertices(scene, transforms, points, args.facing, scene.triangles)
    parameter_axes_into(pose, transforms, args.axes, args.pivots)
    samples = 0
    for e in range(args.edges.shape[0]):
        f0, f1 = args.edge_faces[e, 0], args.edge_faces[e, 1]
        fa, fb = args.facing[f0], args.facing[f1]
        if fa < 0 or fb < 0 or fa == fb:
            continue                                   # not a contour generator
        front = f0 if fa == 1 else f1
        part = scene.triangle_part[front]
        c_in = np.int64(scene.part_label[part])
        a, b = args.edges[e, 0], args.edges[e, 1]
        w = scene.triangles[front, 0] + scene.triangles[front, 1] + scene.triangles[front, 2] - a - b
        seg = scene.vertex_segment[a]
        ua, va = cam[0] * points[a, 0] / points[a, 2] + cam[2], cam[1] * points[a, 1] / points[a, 2] + cam[3]
        ub, vb = cam[0] * points[b, 0] / points[b, 2] + cam[2], cam[1] * points[b, 1] / points[b, 2] + cam[3]
        uw, vw = cam[0] * points[w, 0] / points[w, 2] + cam[2], cam[1] * points[w, 1] / points[w, 2] + cam[3]
        length = np.sqrt((ub - ua) ** 2 + (vb - va) ** 2)
        if length == 0.0:
            continue
        nu, nv = (vb - va) / length, -(ub - ua) / length   # unit normal, turned outwards below
        if nu * (uw - ua) + nv * (vw - va) > 0.0:
            nu, nv = -nu, -nv
        n_s = max(np.int64(np.ceil(length / args.spacing)), 1)
        ds = length / n_s
        for j in range(n_s):
            t = (j + 0.5) / n_s
            x = (1.0 - t) * points[a, 0] + t * points[b, 0]
            y = (1.0 - t) * points[a, 1] + t * points[b, 1]
            z = (1.0 - t) * points[a, 2] + t * points[b, 2]
            iz = 1.0 / z
            u, v = cam[0] * x * iz + cam[2], cam[1] * y * iz + cam[3]
            # the part itself just inside, something of another class (not nearer) just outside
            pi, qi = np.int64(np.floor(u - 0.75 * nu)), np.int64(np.floor(v - 0.75 * nv))
            po, qo = np.int64(np.floor(u + 0.75 * nu)), np.int64(np.floor(v + 0.75 * nv))
            if pi < 0 or qi < 0 or pi >= width or qi >= height or part_buf[qi * width + pi] != part + 1:
                continue
            c_out = np.int64(0)
            if 0 <= po < width and 0 <= qo < height:
                o = qo * width + po
                if part_buf[o] != 0:
                    if depth_buf[o] > iz:
                        continue                       # a nearer surface covers the outside
                    c_out = np.int64(scene.part_label[part_buf[o] - 1])
            if c_out == c_in:
                continue                               # the boundary moves within one class: flat
            samples += 1
            counted = _label_share(c.target, width, height, u, v, 0, True) if c.ignore_unknown else 1.0
            hit_in = _label_share(c.target, width, height, u, v, c_in, False)
            hit_out = _label_share(c.target, width, height, u, v, c_out, False) if c_out > 0 else 0.0
            wx, wy = nu * cam[0] * iz, nv * cam[1] * iz
            wz = -(wx * x + wy * y) * iz
            point_jacobian_into(x, y, z, seg, args.axes, args.pivots, args.moves, jac)
            for k in range(n_par):
                normal_speed = (wx * jac[0, k] + wy * jac[1, k] + wz * jac[2, k]) * ds
                d_model[c_in, k] += counted * normal_speed
                d_overlap[c_in, k] += hit_in * normal_speed
                if c_out > 0:
                    d_model[c_out, k] -= counted * normal_speed
                    d_overlap[c_out, k] -= hit_out * normal_speed
    samples += _seam_rates(scene, buffers, args, c.target, c.ignore_unknown)
    _region_counts_and_clear(part_buf, depth_buf, scene.part_label, width, buffers.box, c.target, c.n_classes,
                             c.model_count, c.overlap_count, c.ignore_unknown)
    value = _non_overlapping_ratio(c.target_count, c.model_count, c.overlap_count, c.n_classes)
    for k in range(n_par):
        gradient[k] = 0.0
    used = 0
    for cl in range(1, c.n_classes + 1):
        union = c.target_count[cl] + c.model_count[cl] - c.overlap_count[cl]
        if union == 0:
            continue
        used += 1
        miss = union - c.overlap_count[cl]
        for k in range(n_par):
            d_union = d_model[cl, k] - d_overlap[cl, k]
            if miss == 0:
                gradient[k] -= d_union / (union + 1.0)
            else:
                gradient[k] += (d_union - d_overlap[cl, k]) / miss - d_union / union
    if used == 0 or value == 0.0:
        for k in range(n_par):
            gradient[k] = 0.0
        return value, samples
    for k in range(n_par):
        gradient[k] *= value / used
    return value, samples


@jit
def _robust(d, scale):
    """:func:`robust_distance` of one distance ``d`` at ``scale`` (pixels; inf: ``d`` itself)."""
    if scale == np.inf:
        return d
    return scale * np.log1p(d / scale)


@jit
def _joint_distance(t, cam, s, local, i, u, v, behind_penalty):
    """Pixel distance from keypoint (u, v) to the projection of the point ``local[i]`` of segment
    ``s`` (transforms ``t``); ``behind_penalty`` when it is nearer than the near plane."""
    x = t[s, 0, 0] * local[i, 0] + t[s, 0, 1] * local[i, 1] + t[s, 0, 2] * local[i, 2] + t[s, 0, 3]
    y = t[s, 1, 0] * local[i, 0] + t[s, 1, 1] * local[i, 1] + t[s, 1, 2] * local[i, 2] + t[s, 1, 3]
    z = t[s, 2, 0] * local[i, 0] + t[s, 2, 1] * local[i, 1] + t[s, 2, 2] * local[i, 2] + t[s, 2, 3]
    if z < cam[4]:
        return behind_penalty
    du = cam[0] * x / z + cam[2] - u
    dv = cam[1] * y / z + cam[3] - v
    return np.sqrt(du * du + dv * dv)


@jit
def keypoint_labellings_kernel(pose, args):
    """Compiled D_k(pose) under the detector's labelling and under the swapped one (pixels),
    for an unchecked float64 (23,) pose and a :class:`KeypointKernelArgs`: ``(detector,
    swapped)``, the second 0 when ``args.swap`` is off (both 0 with no keypoint)."""
    segment_transforms_into(pose, args.offsets, args.transforms)
    t, cam = args.transforms, args.camera
    direct = 0.0
    swapped = 0.0
    for i in range(args.uv.shape[0]):
        d = _joint_distance(t, cam, args.joint_segment[i], args.joint_local, i, args.uv[i, 0], args.uv[i, 1],
                            args.behind_penalty)
        direct += args.weight[i] * _robust(d, args.scale[i])
    if args.swap:
        for k in range(args.uv.shape[0]):
            i = args.swapped_order[k]
            d = _joint_distance(t, cam, args.swapped_segment[i], args.swapped_local, i, args.uv[i, 0], args.uv[i, 1],
                                args.behind_penalty)
            swapped += args.weight[i] * _robust(d, args.scale[i])
    return direct, swapped


@jit
def keypoint_cost_kernel(pose, args):
    """Compiled D_k(pose), pixels, for an unchecked float64 (23,) pose and a
    :class:`KeypointKernelArgs` (0 with no keypoint): the detector's labelling, or with
    ``args.swap`` the lower of it and the swapped one."""
    direct, swapped = keypoint_labellings_kernel(pose, args)
    if args.swap and swapped < direct:
        return swapped
    return direct


@jit
def _render_labels(pose, scene, buffers, out_box):
    """Render class labels straight into the part buffer ``buffers.part_ids`` (the scene's
    triangle parts must be each triangle's label - 1) and reset the depth buffer.

    The part buffer must be 0 outside the inclusive pixel box ``out_box`` (x0, y0, x1, y1;
    x0 > x1 for none), as this function leaves it: the previous render is cleared from that
    box first, and the box becomes the new render's one.
    """
    part_buf, depth_buf, bbox = buffers.part_ids, buffers.inverse_depth, buffers.box
    width = scene.width
    for py in range(out_box[1], out_box[3] + 1):
        row = py * width
        part_buf[row + out_box[0]: row + out_box[2] + 1] = 0
    render_scene_into(pose, scene, buffers)
    for py in range(bbox[1], bbox[3] + 1):
        row = py * width
        depth_buf[row + bbox[0]: row + bbox[2] + 1] = 0.0
    out_box[0], out_box[1], out_box[2], out_box[3] = bbox[0], bbox[1], bbox[2], bbox[3]


@jit
def _render_labels_if_finite(pose, offsets, vertices, vertex_segment, triangles, triangle_part, part_label, camera,
                             width, height, part_ids, inverse_depth, vertex_x, vertex_y, vertex_inverse_depth,
                             transforms, box, triangle_ids, coverage, out_box):
    """:func:`_render_labels` of a float64 (23,) ``pose`` whose sum is finite (then True; else
    False and nothing rendered: the caller checks it), with the fields of the
    :class:`~mocap.render.rasterize.Scene` and :class:`~mocap.render.rasterize.Buffers` as
    arrays: Numba's dispatcher types arrays in C but named tuples in Python (3.4 µs a call,
    against about 1 for the arrays)."""
    total = 0.0
    for value in pose:
        total += value
    if not np.isfinite(total):
        return False
    scene = Scene(offsets, vertices, vertex_segment, triangles, triangle_part, part_label, camera, width, height)
    buffers = Buffers(part_ids, inverse_depth, vertex_x, vertex_y, vertex_inverse_depth, transforms, box,
                      triangle_ids, coverage)
    _render_labels(pose, scene, buffers, out_box)
    return True


_FLOAT64 = np.dtype(np.float64)


# ----------------------------------------------------------------------------- public
class LabelRenderer:
    """Repeated coloured-silhouette renders into preallocated buffers (no allocation per call).

    Parameters
    ----------
    model : BodyModel
    camera : Camera

    ``renderer(pose)`` returns the class-label image, uint8 (height, width), as a read-only view
    of the buffer the next call renders into (copy it to keep it). The labels are rasterized
    straight into that buffer, and each call clears only the previous render's bounding box,
    so the buffer must not be changed from outside: that is why the view is read-only. Not
    thread-safe: one object per thread.
    """

    def __init__(self, model: BodyModel, camera: Camera) -> None:
        self.model, self.camera = model, camera
        # rasterize labels, not parts: triangle "part" = label - 1, which the rasterizer draws as label
        triangle_label = model.part_label[model.mesh.triangle_part].astype(np.int64) - 1
        self._scene = Scene.of(model, camera)._replace(triangle_part=triangle_label)
        self._buffers = Buffers.of(model, camera)
        self._out_box = np.array([camera.width, camera.height, -1, -1], np.int64)   # nothing drawn
        self._labels = self._buffers.part_ids.reshape(camera.shape)
        self._labels.flags.writeable = False
        self._arrays = (*self._scene, *self._buffers, self._out_box)

    def __call__(self, pose) -> np.ndarray:
        # a writeable C-contiguous float64 (23,) array with a finite sum is a valid pose (what
        # check_pose tests, without its copy); anything else goes through check_pose
        fast = type(pose) is np.ndarray and pose.dtype == _FLOAT64 and pose.shape == (N_PARAMETERS,)
        if fast:
            flags = pose.flags
            fast = flags.c_contiguous and flags.writeable and flags.aligned
        if not (fast and _render_labels_if_finite(pose, *self._arrays)):
            _render_labels(check_pose(pose), self._scene, self._buffers, self._out_box)
        return self._labels


def _part_segments(mesh) -> np.ndarray:
    """Segment of each mesh part (0 for a part without triangles), int64 (parts,)."""
    out = np.zeros(int(mesh.triangle_part.max()) + 1, np.int64)
    out[mesh.triangle_part] = mesh.vertex_segment[mesh.triangles[:, 0]]
    return out


def _check_image(image: np.ndarray, camera: Camera, what: str) -> None:
    if not isinstance(image, np.ndarray) or image.shape != camera.shape:
        shape = getattr(image, "shape", None)
        raise ValueError(f"{what} must be an array of shape {camera.shape} (height, width) matching the "
                         f"camera, got {shape}")


class RegionCost:
    """Non-overlapping ratio F(q) (eq. 1) against a segmented label image.

    Parameters
    ----------
    target_labels : ndarray, shape (height, width), uint8
        Segmented frame (:mod:`mocap.labels`: 0 background, 1..m classes, 255 unknown).
    model : BodyModel
        Its ``class_names`` give m.
    camera : Camera
        Must match the image size.
    ignore_unknown : bool
        Model pixels over image pixels labelled unknown (255) are left out of B_c (default).
        The paper's segmentation puts every foreground pixel in a class; ours leaves the ones no
        class explains (blurred boundaries, colours of unmodelled parts) unknown. Counting a
        model pixel over them as a mismatch, while the unknown pixels the model leaves uncovered
        cost nothing, rewards a shrunken model: a steady drift away from the camera when
        tracking. With ``False``, eq. (1) is applied literally to the label image.

    Calling ``cost(pose)`` with a (23,) pose (metres, radians) returns F in [0, 1]:
    0 for a perfect match of every class, 1 for no overlap.
    """

    def __init__(self, target_labels: np.ndarray, model: BodyModel, camera: Camera, *,
                 ignore_unknown: bool = True) -> None:
        _check_image(target_labels, camera, "target label image")
        if target_labels.dtype != np.uint8:
            raise ValueError(f"target label image must be uint8, got {target_labels.dtype}")
        m = model.n_classes
        if not 1 <= m <= MAX_CLASSES:
            raise ValueError(f"model must have 1..{MAX_CLASSES} colour classes, got {m}")
        self.model, self.camera, self.n_classes = model, camera, m
        self._target = np.ascontiguousarray(target_labels).ravel()
        counts = np.bincount(self._target, minlength=256).astype(np.int64)
        self.target_count = counts[: m + 1].copy()
        self.target_count[0] = 0
        self._scene = Scene.of(model, camera)
        self._buffers = Buffers.of(model, camera)
        self._model_count = np.zeros(m + 1, np.int64)
        self._overlap_count = np.zeros(m + 1, np.int64)
        self.ignore_unknown = bool(ignore_unknown)
        self._gradient_args: RegionGradientArgs | None = None

    def __call__(self, pose) -> float:
        return float(self.evaluate_unchecked(check_pose(pose)))

    def evaluate_unchecked(self, pose: np.ndarray) -> float:
        """As calling, without validating ``pose`` (a float64 (23,) array): for optimiser loops."""
        return region_cost_kernel(pose, self.kernel_args())

    def for_model(self, model: BodyModel) -> "RegionCost":
        """The same target on another body model with the same colour classes (other
        proportions, as a calibration's fit tries): the value a new ``RegionCost`` of ``model``
        would give at every pose, without recounting the target's classes. The copy has
        scratch buffers of its own.

        Raises
        ------
        ValueError
            If ``model`` has another number of colour classes.
        """
        if model.n_classes != self.n_classes:
            raise ValueError(f"model has {model.n_classes} colour classes, this cost {self.n_classes}")
        return self._twin(model, Scene.of(model, self.camera))

    def spare(self) -> "RegionCost":
        """The same cost with scratch buffers of its own, for another thread (the target and
        the scene are shared, read-only); it gives the same value at every pose."""
        return self._twin(self.model, self._scene)

    def _twin(self, model: BodyModel, scene: Scene) -> "RegionCost":
        """This cost's target on ``model`` drawn as ``scene``, with scratch buffers of its own."""
        twin = copy.copy(self)
        twin.model, twin._scene, twin._buffers = model, scene, Buffers.of(model, self.camera)
        twin._model_count, twin._overlap_count = np.zeros_like(self._model_count), np.zeros_like(self._overlap_count)
        twin._gradient_args = None
        return twin

    def kernel_args(self) -> RegionKernelArgs:
        """Second argument of :func:`region_cost_kernel` (for compiled optimiser loops)."""
        return RegionKernelArgs(self._scene, self._buffers, self._target, self.target_count, self.n_classes,
                                self._model_count, self._overlap_count, self.ignore_unknown)

    def gradient(self, pose) -> RegionGradient:
        """F and its gradient with respect to the 23 pose parameters, from one render.

        Parameters
        ----------
        pose : array_like, shape (23,)
            Metres and radians.

        Returns
        -------
        RegionGradient
            See there for the method (boundary motion times the change of each class's union
            and intersection; flat where no boundary moves a class).
        """
        out = np.zeros(N_PARAMETERS)
        value, samples = self.gradient_unchecked(check_pose(pose), out)
        return RegionGradient(float(value), out, int(samples))

    def gradient_unchecked(self, pose: np.ndarray, out: np.ndarray) -> tuple[float, int]:
        """As :meth:`gradient` without validation, the gradient written into ``out`` (float64 (23,)):
        returns ``(value, samples)``. For optimiser loops."""
        return region_gradient_kernel(pose, self.gradient_args(), out)

    def gradient_args(self) -> RegionGradientArgs:
        """Second argument of :func:`region_gradient_kernel` (built on first use, then kept)."""
        if self._gradient_args is None:
            mesh = self.model.mesh
            edges, faces = edge_faces(mesh.triangles)
            m = self.n_classes
            self._gradient_args = RegionGradientArgs(
                self.kernel_args(), edges, faces, PARAMETER_MOVES, np.empty((len(mesh.vertices), 3)),
                np.empty(len(mesh.triangles), np.int8), np.empty((N_PARAMETERS, 3)), np.empty((N_PARAMETERS, 3)),
                np.empty((3, N_PARAMETERS)), CONTOUR_SPACING_PX, np.zeros((m + 1, N_PARAMETERS)),
                np.zeros((m + 1, N_PARAMETERS)), _part_segments(mesh), EDGE_DEPTH_GAP_M, np.empty((3, N_PARAMETERS)))
        return self._gradient_args


class EdgeCost:
    """Mean edge distance D_c (eq. 2) against an image's distance-to-edge map.

    Parameters
    ----------
    distance : ndarray, shape (height, width), float
        Distance of every pixel to the nearest image edge, pixels (truncated).
    model : BodyModel
    camera : Camera
    edge_gap : float, metres
        Depth gap that makes a part boundary an occluding contour.
    no_edge_penalty : float, pixels, optional
        Value when the model shows no edge pixel; defaults to ``distance.max()``.

    Calling ``cost(pose)`` returns D_c in pixels (>= 0).
    """

    def __init__(self, distance: np.ndarray, model: BodyModel, camera: Camera, *,
                 edge_gap: float = EDGE_DEPTH_GAP_M, no_edge_penalty: float | None = None) -> None:
        _check_image(distance, camera, "distance map")
        d = np.ascontiguousarray(distance, dtype=np.float32)
        if not np.isfinite(d).all() or (d < 0).any():
            raise ValueError("distance map must be finite and non-negative")
        penalty = float(d.max()) if no_edge_penalty is None else float(no_edge_penalty)
        if not np.isfinite(penalty) or penalty < 0:
            raise ValueError(f"no_edge_penalty must be finite and non-negative, got {no_edge_penalty}")
        self.model, self.camera = model, camera
        self.edge_gap = check_edge_gap(edge_gap)
        self.no_edge_penalty = penalty
        self._distance = d.ravel()
        self._scene = Scene.of(model, camera)
        self._buffers = Buffers.of(model, camera)
        self._marks = np.zeros(camera.width * camera.height, np.bool_)
        self._gradient_args: EdgeGradientArgs | None = None

    def __call__(self, pose) -> float:
        return float(self.evaluate_unchecked(check_pose(pose)))

    def evaluate_unchecked(self, pose: np.ndarray) -> float:
        """As calling, without validating ``pose`` (a float64 (23,) array): for optimiser loops."""
        return edge_cost_kernel(pose, self.kernel_args())

    def spare(self) -> "EdgeCost":
        """The same cost with scratch buffers of its own, for another thread (the distance map
        and the scene are shared, read-only); it gives the same value at every pose."""
        twin = copy.copy(self)
        twin._buffers = Buffers.of(self.model, self.camera)
        twin._marks = np.zeros_like(self._marks)
        twin._gradient_args = None
        return twin

    def kernel_args(self) -> EdgeKernelArgs:
        """Second argument of :func:`edge_cost_kernel` (for compiled optimiser loops)."""
        return EdgeKernelArgs(self._scene, self._buffers, self._distance, self._marks, self.edge_gap,
                              self.no_edge_penalty)

    def gradient(self, pose) -> EdgeGradient:
        """D_c and its gradient with respect to the 23 pose parameters, from one render.

        Parameters
        ----------
        pose : array_like, shape (23,)
            Metres and radians.

        Returns
        -------
        EdgeGradient
            See there for what is differentiated (the contour mean) and how.
        """
        out = np.zeros(N_PARAMETERS)
        value, contour_value, samples = self.gradient_unchecked(check_pose(pose), out)
        return EdgeGradient(float(value), float(contour_value), out, int(samples))

    def gradient_unchecked(self, pose: np.ndarray, out: np.ndarray) -> tuple[float, float, int]:
        """As :meth:`gradient` without validation, the gradient written into ``out`` (float64 (23,)):
        returns ``(value, contour_value, samples)``. For optimiser loops."""
        return edge_gradient_kernel(pose, self.gradient_args(), out)

    def gradient_args(self) -> EdgeGradientArgs:
        """Second argument of :func:`edge_gradient_kernel` (built on first use, then kept)."""
        if self._gradient_args is None:
            h, w = self.camera.shape
            gv, gu = np.gradient(self._distance.reshape(h, w).astype(np.float64))
            mesh = self.model.mesh
            edges, faces = edge_faces(mesh.triangles)
            self._gradient_args = EdgeGradientArgs(
                self.kernel_args(), np.ascontiguousarray(gu).ravel(), np.ascontiguousarray(gv).ravel(), edges, faces,
                PARAMETER_MOVES, np.empty((len(mesh.vertices), 3)), np.empty(len(mesh.triangles), np.int8),
                np.empty((N_PARAMETERS, 3)), np.empty((N_PARAMETERS, 3)), np.empty((3, N_PARAMETERS)),
                CONTOUR_SPACING_PX)
        return self._gradient_args


@dataclass(frozen=True)
class EdgeGradient:
    """Gradient of the mean edge distance (eq. 2) at one pose (:meth:`EdgeCost.gradient`).

    Eq. (2) averages the distance map over the model's occluding-edge *pixels*, a set that
    changes by whole pixels: as a function of the pose it is piecewise constant. Its gradient is
    taken as that of its continuous counterpart, the mean of the distance map over the model's
    occluding contour: the mesh edges between a front- and a back-facing triangle, sampled every
    ``spacing`` pixels or less once projected, kept where the rendered occluding-edge mask marks
    the sample's pixel or a 4-neighbour (visible, and an occluding edge by the render's depth-gap
    rule), with the distance and its gradient read by bilinear interpolation. Each sample moves
    with its body segment (analytic Jacobian of :mod:`mocap.body.kinematics`) through the
    pinhole projection. The change of the visible set and of the sample count is not
    differentiated.

    Attributes
    ----------
    value : float, pixels
        D_c (eq. 2) at the pose, exactly as :class:`EdgeCost` computes it.
    contour_value : float, pixels
        The contour mean whose gradient ``gradient`` is (the ``no_edge_penalty`` without any
        visible sample).
    gradient : ndarray, shape (23,), float64
        d contour_value / dq: pixels per metre (root positions), pixels per radian (angles);
        zero without a visible sample.
    samples : int
        Visible contour samples.
    """

    value: float
    contour_value: float
    gradient: np.ndarray
    samples: int


@dataclass(frozen=True)
class RegionGradient:
    """Gradient of the non-overlapping ratio F (eq. 1) at one pose (:meth:`RegionCost.gradient`).

    F counts whole pixels, so as a function of the pose it is piecewise constant; its gradient
    is that of the areas it counts moving with the silhouette's boundary, as OpenDR and de La
    Gorce et al. (PAMI 2011) differentiate a rendered region: the model's occluding contour (mesh
    edges between a front- and a back-facing triangle, :class:`EdgeGradient`) is sampled every
    pixel or less; a sample counts where the render shows its own part just inside it and
    background or a part of another colour class, not nearer, just outside (elsewhere the
    boundary is hidden, or moves between pixels of one class: flat). Moving outwards by one
    pixel, a sample's length ``ds`` of boundary turns that much area from the outside class to
    the inside one: |B_in| grows and |B_out| shrinks by ``ds`` (times the share of target pixels
    there that are not unknown, with ``ignore_unknown``), |A_in ∩ B_in| grows by ``ds`` times the
    share of target pixels of the inside class there (bilinear), |A_out ∩ B_out| shrinks by
    ``ds`` times that of the outside class. The outward normal speed of each sample under each
    parameter (analytic Jacobians of :mod:`mocap.body.kinematics`, pinhole projection) carries
    these into d|B_c|/dq and d|A_c ∩ B_c|/dq, and those through eq. (1) (the empty-union and
    exact-match rules of :class:`RegionCost` included) into dF/dq. Boundaries between two parts
    of different classes with no occluding depth step (seams: the face and hair cut, a neck
    entering the torso) are not contours; they are found in the render, between 4-neighbour
    pixels, and move with the average of the two surface points seen there.

    The gradient is zero where no boundary moves a class: a model out of view, or F = 0.

    Attributes
    ----------
    value : float
        F at the pose, exactly as :class:`RegionCost` computes it.
    gradient : ndarray, shape (23,), float64
        dF/dq: per metre (root positions), per radian (angles).
    samples : int
        Boundary samples that moved a class.
    """

    value: float
    gradient: np.ndarray
    samples: int


#: Largest distance between two contour samples of :meth:`EdgeCost.gradient`, pixels.
CONTOUR_SPACING_PX = 1.0


#: The detector's measured 2D noise per joint (:data:`~mocap.body.skeleton.JOINT_NAMES`), in units
#: of the ten joints' RMS distance from their mean: MediaPipe Pose on renders of held-out motion
#: capture, 1.4826 MAD per coordinate (``experiments/lifter_keypoint_noise.json``,
#: ``python -m experiments.lifter_keypoint_noise``). MediaPipe gives no neck; its value is the
#: shoulders'. Each side's twins have the two sides' mean (the sides differ by the measure's own
#: noise, and the labels are what the tracker does not take from the detector): the cost of
#: keypoints whose left and right are swapped is then the same under the other labelling.
KEYPOINT_NOISE = MappingProxyType({
    "head": 0.0309, "neck": 0.0744,
    "r_shoulder": 0.0744, "r_elbow": 0.0977, "r_wrist": 0.1052, "r_hand": 0.1537,
    "l_shoulder": 0.0744, "l_elbow": 0.0977, "l_wrist": 0.1052, "l_hand": 0.1537,
})
#: Least robust scale of a keypoint, pixels: a detector's pixel grid and the model's joints' own
#: definitions put a keypoint this far off even where the noise above is smaller (the oracle's
#: 2 px per coordinate is about as much). At 160x120 the noise times the person's spread (about
#: 34 px) is 1-5 px. This robust scale costs the true-2D figures (seed 71: 80 mm and 30.1 % of
#: frames over 100 mm against 71 mm and 26.0 % with the plain distance); a 12 px floor did better
#: on six sequences but four recovery tests failed with it (docs/research-log.md, 2026-11-28).
MIN_KEYPOINT_SCALE_PX = 3.0
#: Distance off the person's region within which a keypoint is not gated down, pixels (the pixel
#: grid, and a keypoint on the silhouette's edge with the oracle's 2 px of noise).
GATE_MARGIN_PX = 3.0


def robust_distance(d, scale):
    """The keypoint term's robust distance: ``scale * log(1 + d / scale)`` (pixels).

    Near a keypoint it is the distance itself (slope 1, so the term's weight means what it meant
    for the plain distance); far away it grows as the logarithm, and the pull of a joint (the
    slope, ``scale / (scale + d)``) falls off as ``scale / d``: a joint 50 px off pulls at
    ``scale / (scale + 50)`` of a near one's rate (6 % at the 3 px of
    :data:`MIN_KEYPOINT_SCALE_PX`; the silhouette's gate, :func:`keypoint_gates`, does the rest).
    It is the L1 form of the Cauchy (Lorentzian) loss, whose negative log-likelihood ``log(1 + (d / scale)^2)`` would make the term quadratic near
    the keypoint and change its balance with the image's terms.

    Parameters
    ----------
    d : float or ndarray, pixels (>= 0)
    scale : float or ndarray, pixels (> 0; inf gives ``d``)

    Returns
    -------
    float or ndarray, pixels
    """
    d, scale = np.asarray(d, dtype=np.float64), np.asarray(scale, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        out = np.where(np.isinf(scale), d, scale * np.log1p(d / np.where(np.isinf(scale), 1.0, scale)))
    return out[()] if out.ndim == 0 else out


def keypoint_scales(uv, confidence) -> np.ndarray:
    """Each keypoint's robust scale (pixels): :data:`KEYPOINT_NOISE` times the present keypoints'
    RMS distance from their mean (the person's size in the image, as the noise was measured), at
    least :data:`MIN_KEYPOINT_SCALE_PX`. The spread is computed over the keypoints sorted by
    position, so that the same keypoints under other labels give the same floats.

    Parameters
    ----------
    uv : ndarray, shape (10, 2), float, pixels (NaN where absent)
    confidence : ndarray, shape (10,), in [0, 1] (0 where absent)

    Returns
    -------
    ndarray, shape (10,), float64, pixels
    """
    uv, conf = np.asarray(uv, dtype=np.float64), np.asarray(confidence, dtype=np.float64)
    present = (np.nan_to_num(conf) > 0) & np.isfinite(uv).all(axis=1)
    spread = 0.0
    if present.sum() >= 2:
        p = uv[present]
        p = p[np.lexsort((p[:, 1], p[:, 0]))]
        spread = float(np.sqrt(((p - p.mean(axis=0)) ** 2).sum(axis=1).mean()))
    noise = np.array([KEYPOINT_NOISE[name] for name in JOINT_NAMES])
    return np.maximum(noise * spread, MIN_KEYPOINT_SCALE_PX)


def keypoint_gates(uv, foreground, margin: float = GATE_MARGIN_PX) -> np.ndarray:
    """Each keypoint's silhouette gate in (0, 1]: 1 on the person's region or within ``margin``
    of it, else ``1 / (1 + ((o - margin) / margin)^2)`` with ``o`` its distance to the region
    (pixels): a joint 50 px outside weighs 0.4 % of one on the person. Without a region (no
    foreground pixel) every gate is 1.

    Parameters
    ----------
    uv : ndarray, shape (n, 2), float, pixels
        Keypoints (finite), pixel centres at half-integers.
    foreground : ndarray, shape (H, W), bool
        The person's region (a label image's pixels other than background).
    margin : float, pixels (> 0)

    Returns
    -------
    ndarray, shape (n,), float64
    """
    from scipy.ndimage import distance_transform_edt

    uv = np.asarray(uv, dtype=np.float64)
    if not (np.isfinite(margin) and margin > 0):
        raise ValueError(f"margin must be finite and positive, got {margin!r}")
    fg = np.asarray(foreground, dtype=bool)
    if fg.ndim != 2:
        raise ValueError(f"foreground must be a 2-D mask, got shape {fg.shape}")
    gates = np.ones(len(uv))
    if len(uv) == 0 or not fg.any():
        return gates
    h, w = fg.shape
    col = np.clip(np.floor(uv[:, 0]).astype(np.int64), 0, w - 1)
    row = np.clip(np.floor(uv[:, 1]).astype(np.int64), 0, h - 1)
    # beyond the image: the distance to the border pixel plus that pixel's to the region
    beyond = np.hypot(np.maximum(np.maximum(-uv[:, 0], uv[:, 0] - w), 0.0),
                      np.maximum(np.maximum(-uv[:, 1], uv[:, 1] - h), 0.0))
    if fg[row, col].all() and not beyond.any():
        return gates
    outside = distance_transform_edt(~fg)[row, col] + beyond
    excess = np.maximum(outside - margin, 0.0) / margin
    return 1.0 / (1.0 + excess ** 2)


class KeypointCost:
    """Keypoint distance D_k: the weighted mean robust distance of the projected joints.

    Parameters
    ----------
    uv : ndarray, shape (10, 2), float, pixels
        A keypoint per joint of :data:`~mocap.body.skeleton.JOINT_NAMES` in the camera's
        pixels; NaN where absent.
    confidence : ndarray, shape (10,), float
        In [0, 1]; 0 (or NaN) where absent.
    model : BodyModel
    camera : Camera
    foreground : ndarray, shape (H, W), bool, optional
        The person's region in the camera's image (the frame's label image other than
        background): a keypoint off it is gated down (:func:`keypoint_gates`). None: no gate.
    scale : ndarray, shape (10,), float, pixels, optional
        Each keypoint's robust scale (default :func:`keypoint_scales`; inf: the plain pixel
        distance).
    swap : bool
        Also score the keypoints with left and right swapped (:data:`~mocap.io.keypoints.SWAPPED_JOINTS`):
        the cost is the lower of the two labellings, and :meth:`labelling` tells which.

    Calling ``cost(pose)`` returns ``sum_j w_j rho_j(|pi(J_j(pose)) - k_j|)`` over the present
    joints j, pixels (>= 0; 0 when no joint is present or the keypoints are the model's own
    projections): ``rho_j`` :func:`robust_distance` at the joint's scale, ``w_j`` its confidence
    times its gate over the sum of those products. A joint nearer than the camera's near plane
    counts the image diagonal.
    """

    def __init__(self, uv: np.ndarray, confidence: np.ndarray, model: BodyModel, camera: Camera, *,
                 foreground: np.ndarray | None = None, scale: np.ndarray | None = None, swap: bool = False) -> None:
        uv, conf = np.asarray(uv, dtype=np.float64), np.asarray(confidence, dtype=np.float64)
        if uv.shape != (len(JOINT_NAMES), 2) or conf.shape != (len(JOINT_NAMES),):
            raise ValueError(f"keypoints need uv of shape ({len(JOINT_NAMES)}, 2) and confidence of shape "
                             f"({len(JOINT_NAMES)},), got {uv.shape} and {conf.shape}")
        conf = np.where(np.isnan(conf), 0.0, conf)
        if np.any(conf < 0) or np.any(conf > 1) or np.any(np.isinf(uv)):
            raise ValueError("keypoint confidences must be in [0, 1] and positions finite or NaN")
        scale = keypoint_scales(uv, conf) if scale is None else np.asarray(scale, dtype=np.float64)
        if scale.shape != (len(JOINT_NAMES),) or np.any(np.isnan(scale)) or np.any(scale <= 0):
            raise ValueError(f"keypoint scales must be {len(JOINT_NAMES)} positive numbers, got {scale!r}")
        if foreground is not None and np.shape(foreground) != camera.shape:
            raise ValueError(f"foreground of shape {np.shape(foreground)} does not match the camera {camera.shape}")
        if not isinstance(swap, (bool, np.bool_)):
            raise ValueError(f"swap must be true or false, got {swap!r}")
        present = (conf > 0) & np.isfinite(uv).all(axis=1)
        self.camera = camera
        self.present = present
        self.swap = bool(swap)
        self._uv = np.ascontiguousarray(uv[present])
        self._scale = np.ascontiguousarray(scale[present])
        gate = np.ones(len(self._uv)) if foreground is None else keypoint_gates(self._uv, foreground)
        #: Each present keypoint's silhouette gate (:func:`keypoint_gates`; 1 without a foreground).
        self.gates = gate
        weight = conf[present] * gate
        total = np.sort(weight).sum()                     # the same float whatever the labels' order
        self._weight = weight / total if total > 0 else np.zeros(0)
        self._joints = np.flatnonzero(present)
        self._twins = np.array([SWAPPED_JOINTS[j] for j in self._joints], dtype=np.int64)
        self._swapped_order = np.argsort(self._twins, kind="stable").astype(np.int64)
        self._bind_joints(model)
        self._transforms = np.zeros((len(SEGMENT_NAMES), 3, 4))
        self._camera = camera.as_array()
        self.behind_penalty = float(np.hypot(camera.width, camera.height))

    def _bind_joints(self, model: BodyModel) -> None:
        """Read the present joints' (and their left/right twins') segments and places off
        ``model``'s skeleton."""
        skeleton = model.skeleton
        self.model = model
        self._segment = skeleton.joint_segment[self._joints]
        self._local = skeleton.joint_local[self._joints]
        self._swapped_segment = skeleton.joint_segment[self._twins]
        self._swapped_local = skeleton.joint_local[self._twins]

    def for_model(self, model: BodyModel) -> "KeypointCost":
        """The same keypoints, scales, gates and labellings on another body model (other
        proportions, as a calibration's fit tries): the value a new ``KeypointCost`` of ``model``
        would give at every pose, without recomputing the gates' distance transform. The copy
        has a scratch buffer of its own."""
        twin = self.spare()
        twin._bind_joints(model)
        return twin

    @property
    def empty(self) -> bool:
        """Whether no keypoint is present (the cost is then 0 everywhere)."""
        return len(self._uv) == 0

    def __call__(self, pose) -> float:
        return float(self.evaluate_unchecked(check_pose(pose)))

    def evaluate_unchecked(self, pose: np.ndarray) -> float:
        """As calling, without validating ``pose`` (a float64 (23,) array): for optimiser loops."""
        return keypoint_cost_kernel(pose, self.kernel_args())

    def labellings(self, pose) -> tuple[float, float]:
        """D_k at ``pose`` under the detector's labelling and under the swapped one, pixels (the
        second NaN when ``swap`` is off)."""
        direct, swapped = keypoint_labellings_kernel(check_pose(pose), self.kernel_args())
        return float(direct), (float(swapped) if self.swap else float("nan"))

    def value_and_labelling(self, pose) -> tuple[float, bool]:
        """``(cost(pose), labelling(pose))`` from one evaluation of the two labellings."""
        direct, swapped = keypoint_labellings_kernel(check_pose(pose), self.kernel_args())
        taken = bool(self.swap and swapped < direct)       # as keypoint_cost_kernel decides
        return float(swapped if taken else direct), taken

    def labelling(self, pose) -> bool:
        """Whether the cost at ``pose`` is the swapped labelling's (lower than the detector's; a
        tie keeps the detector's; False when ``swap`` is off)."""
        return self.value_and_labelling(pose)[1]

    def spare(self) -> "KeypointCost":
        """The same cost with a scratch buffer of its own, for another thread (the keypoints are
        shared, read-only); it gives the same value at every pose."""
        twin = copy.copy(self)
        twin._transforms = np.zeros_like(self._transforms)
        return twin

    def kernel_args(self) -> KeypointKernelArgs:
        """Second argument of :func:`keypoint_cost_kernel` (for compiled optimiser loops)."""
        return KeypointKernelArgs(self.model.skeleton.offsets, self._segment, self._local, self._uv, self._weight,
                                  self._camera, self._transforms, self.behind_penalty, self._scale, self.swap,
                                  self._swapped_segment, self._swapped_local, self._swapped_order)


def non_overlapping_ratio(target_labels: np.ndarray, model_labels: np.ndarray, n_classes: int, *,
                          ignore_unknown: bool = True) -> float:
    """Eq. (1) between two label images (no rendering), with the same empty-union rule.

    Parameters
    ----------
    target_labels, model_labels : ndarray, shape (H, W), uint8
    n_classes : int
        m; labels 1..m are classes, anything else is ignored.
    ignore_unknown : bool
        Leave model pixels over unknown (255) target pixels out, as :class:`RegionCost` does.

    Returns
    -------
    float in [0, 1]
    """
    a, b = np.asarray(target_labels), np.asarray(model_labels)
    if a.shape != b.shape or a.ndim != 2:
        raise ValueError(f"label images must be 2-D and of one shape, got {a.shape} and {b.shape}")
    if not 1 <= n_classes <= MAX_CLASSES:
        raise ValueError(f"n_classes must be in 1..{MAX_CLASSES}, got {n_classes}")
    cls = np.arange(n_classes + 1)
    ta = np.array([np.count_nonzero(a == c) for c in cls], np.int64)
    counted = (a != UNKNOWN) if ignore_unknown else np.ones(a.shape, bool)
    mb = np.array([np.count_nonzero((b == c) & counted) for c in cls], np.int64)
    ov = np.array([np.count_nonzero((a == c) & (b == c)) for c in cls], np.int64)
    return float(_non_overlapping_ratio(ta, mb, ov, n_classes))


def mean_edge_distance(distance: np.ndarray, edge_mask: np.ndarray, no_edge_penalty: float | None = None) -> float:
    """Eq. (2) from a distance map and a model edge mask (no rendering).

    Parameters
    ----------
    distance : ndarray, shape (H, W), float, pixels
    edge_mask : ndarray, shape (H, W), bool
    no_edge_penalty : float, optional
        Returned when the mask is empty; defaults to ``distance.max()``.
    """
    d, e = np.asarray(distance, dtype=np.float64), np.asarray(edge_mask, dtype=bool)
    if d.shape != e.shape or d.ndim != 2:
        raise ValueError(f"distance map and edge mask must be 2-D and of one shape, got {d.shape}, {e.shape}")
    if not e.any():
        return float(d.max() if no_edge_penalty is None else no_edge_penalty)
    return float(d[e].mean())
