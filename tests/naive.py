"""Slow, obviously-correct pure-NumPy twins of the compiled kernels, for the tests.

Every ``@jit`` kernel of :mod:`mocap` is compared against an independent answer; most twins
are here (sections: body, optimiser, costs, synth, imaging):

=========================================================  ===============================  =====================================
compiled kernel                                            twin                             test
=========================================================  ===============================  =====================================
``body.kinematics`` (segment transforms, points)           :func:`naive_segment_transforms`  ``tests/body/test_kinematics.py``
``body.ik`` (arm reach, Levenberg–Marquardt)               :func:`naive_reach_arm` (scipy)   ``tests/body/test_ik.py``
``body.mesh`` (templates scaled per part; not compiled)    :func:`naive_build_mesh`          ``tests/body/test_mesh_and_dimensions.py``
``optimize`` (ask/tell Nelder–Mead, compiled cost loop)    :func:`naive_nelder_mead`         ``tests/test_optimize.py``
``cost`` (region counts, eq. 1; edge mean, eq. 2)          :func:`naive_non_overlapping_ratio`, ``tests/test_cost.py``
                                                           :func:`naive_mean_edge_distance`
``cost`` (keypoint distance D_k, both labellings)          :func:`naive_keypoint_distance`   ``tests/test_cost.py``
``cost`` (gradient of eq. 2 over the occluding contour)    :func:`naive_edge_gradient`       ``tests/test_cost_gradient.py``
``cost`` (gradient of eq. 1, boundary motion)              :func:`naive_region_gradient`     ``tests/test_cost_gradient.py``
``synth.shading`` (surface samples)                        :func:`naive_surface_samples`     ``tests/synth/test_sequence.py``
``imaging.background`` (change mask)                       :func:`naive_change_mask`         ``tests/imaging/test_background.py``
``imaging.background`` (densest sample)                    :func:`naive_densest_sample`      ``tests/imaging/test_background.py``
``imaging.visual`` (the overlay, in the model's box)       :func:`naive_draw_model`          ``tests/test_own_video.py``
``imaging.visual`` (the overlay's depth insets)            :func:`naive_depth_insets`        ``tests/test_own_video.py``
``imaging.colour`` (HSV, classification)                   :func:`naive_hsv`,                ``tests/imaging/test_colour.py``
                                                           :func:`naive_classify`
``imaging.edges`` (Deriche recursion)                      :func:`naive_deriche_1d`          ``tests/imaging/test_edges.py``
``imaging.edges`` (magnitude, non-maximum suppression,     :func:`naive_deriche_edges`       ``tests/imaging/test_edges.py``
hysteresis)
``imaging.edges`` (chamfer 3-4 and Euclidean distance)     :func:`naive_distance`            ``tests/imaging/test_edges.py``
=========================================================  ===============================  =====================================

Checked elsewhere: the rasterizer and the occluding-edge scan against the NumPy reference
rasterizer of the library (:mod:`mocap.render.reference`, which the package also keeps for
reading; ``tests/render/test_rasterize.py``), the pose prior's compiled density against
scikit-learn's (``tests/body/test_prior.py``) and the decoder against brute force
(``tests/track/test_decode.py``).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from mocap.body.pose import PARAMETER_INDEX as P

# --- body ---


def naive_part_mesh(length, width, depth, *, e_long, e_cross, taper, resolution, start=0.0, axis_sign=1, cuts=()):
    """Twin of :func:`mocap.body.mesh.part_mesh`: the tessellation as first written, a Python
    loop over the longitudes and rings (the library's twin of it makes the triangles once)."""
    from mocap.body.mesh import signed_volume

    def signed_power(x, e):
        return np.sign(x) * np.abs(x) ** e

    n_lon = int(resolution)
    eta = np.linspace(-np.pi / 2, np.pi / 2, n_lon // 2 + 3)[1:-1]
    if cuts:
        cut = np.asarray(cuts, dtype=np.float64)
        eta = eta.copy()
        moved = np.zeros(len(eta), bool)
        extra = []
        for e in np.arcsin(signed_power(2.0 * cut - 1.0, 1.0 / e_long)):
            free = np.flatnonzero(~moved)
            if free.size == 0:
                extra.append(e)
                continue
            k = free[np.argmin(np.abs(eta[free] - e))]
            eta[k], moved[k] = e, True
        eta = np.unique(np.r_[eta, extra])
    rings = len(eta)
    omega = np.linspace(-np.pi, np.pi, n_lon, endpoint=False)
    u = 0.5 * (1.0 + signed_power(np.sin(eta), e_long))
    radial = np.abs(np.cos(eta)) ** e_long
    scale = radial * (1.0 - taper * u)
    cx = signed_power(np.cos(omega), e_cross)
    cz = signed_power(np.sin(omega), e_cross)
    along = start + length * u
    ring = np.stack([
        0.5 * width * scale[:, None] * cx[None, :],
        np.broadcast_to(along[:, None], (rings, n_lon)),
        0.5 * depth * scale[:, None] * cz[None, :],
    ], axis=-1).reshape(-1, 3)
    poles = np.array([[0.0, start, 0.0], [0.0, start + length, 0.0]])
    vertices = np.concatenate([ring, poles])
    vertices[:, 1] *= axis_sign
    south, north = rings * n_lon, rings * n_lon + 1
    tris = []
    for k in range(n_lon):
        k1 = (k + 1) % n_lon
        tris.append((south, k1, k))
        for r in range(rings - 1):
            a, b = r * n_lon + k, r * n_lon + k1
            c, d = a + n_lon, b + n_lon
            tris.append((a, b, d))
            tris.append((a, d, c))
        top = (rings - 1) * n_lon
        tris.append((north, top + k, top + k1))
    triangles = np.array(tris, dtype=np.int64)
    if signed_volume(vertices, triangles) < 0:
        triangles = triangles[:, ::-1].copy()
    return vertices, triangles


def naive_hair_triangles(vertices, triangles, start, length, depth, hairline, axis_sign):
    """Twin of :func:`mocap.body.mesh.hair_triangles`, from the whole centroids."""
    from mocap.body.mesh import HAIR_NAPE_DROP

    centroid = vertices[triangles].mean(axis=1)
    v = (axis_sign * centroid[:, 1] - (start + 0.5 * length)) / (0.5 * length)
    behind = centroid[:, 2] > 1e-9 * depth
    return (v >= hairline) | (behind & (v >= hairline - HAIR_NAPE_DROP))


def naive_build_mesh(dims, resolution):
    """Twin of :func:`mocap.body.mesh.build_mesh`: every part tessellated afresh by
    :func:`naive_part_mesh` and concatenated (the library scales templates made once).
    Returns (vertices, vertex_segment, triangles, triangle_part)."""
    from mocap.body.mesh import PART_SHAPES, hair_cuts, part_resolution
    from mocap.body.skeleton import (MESH_PART_NAMES, PART_SEGMENT, SEGMENT_AXIS_SIGN, SEGMENT_NAMES,
                                     lower_body_span, part_spans)

    spans = part_spans(dims)
    verts, vseg, tris, tpart = [], [], [], []
    offset = 0
    for p, name in enumerate(MESH_PART_NAMES):
        if not dims.has(name):
            continue
        size = dims[name]
        seg = SEGMENT_NAMES.index(PART_SEGMENT[name])
        e_long, e_cross, taper = PART_SHAPES[name]
        if name == "lower_body":
            start, sign = lower_body_span(dims)[0], 1
        else:
            start, sign = spans[p, 0], SEGMENT_AXIS_SIGN[seg]
        cuts = hair_cuts(dims.hairline) if name == "head" and dims.hairline is not None else ()
        v, t = naive_part_mesh(size.length, size.width, size.depth, e_long=e_long, e_cross=e_cross, taper=taper,
                               resolution=part_resolution(name, resolution), start=start, axis_sign=sign, cuts=cuts)
        part = np.full(len(t), p, dtype=np.int64)
        if cuts:
            part[naive_hair_triangles(v, t, start, size.length, size.depth, dims.hairline, sign)] = \
                MESH_PART_NAMES.index("hair")
        verts.append(v)
        vseg.append(np.full(len(v), seg, dtype=np.int64))
        tris.append(t + offset)
        tpart.append(part)
        offset += len(v)
    return np.concatenate(verts), np.concatenate(vseg), np.concatenate(tris), np.concatenate(tpart)


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


# --- optimiser ---


def naive_reach_arm(pose, model, side, target, regularization, scale=0.01):
    """Arm inverse kinematics by scipy's bounded least squares on the same objective as
    :func:`mocap.body.ik.reach_arm`: hand miss / ``scale`` and the pull to the start angles."""
    from scipy.optimize import least_squares

    from mocap.body import JOINT_LIMITS, JOINT_NAMES

    idx = np.array([P[f"{side}_{n}"] for n in ("shoulder_flex", "shoulder_abd", "shoulder_rot", "elbow_flex")])
    lo, hi = JOINT_LIMITS[idx, 0], JOINT_LIMITS[idx, 1]
    start = np.clip(np.asarray(pose, float)[idx], lo, hi)
    hand = JOINT_NAMES.index(f"{side}_hand")

    def residual(a):
        q = np.array(pose, float)
        q[idx] = a
        return np.r_[(model.joint_positions(q)[hand] - target) / scale, np.sqrt(regularization) * (a - start)]

    out = np.array(pose, float)
    out[idx] = least_squares(residual, np.clip(start, lo + 1e-9, hi - 1e-9), bounds=(lo, hi)).x
    return out


def naive_nelder_mead(f, simplex, lower, upper, budget, ftol, coef=(1.0, 2.0, 0.5, 0.5)):
    """Textbook bounded Nelder-Mead, written plainly: returns the list of evaluated points.

    Same rules as mocap.optimize: clip every trial point; reflect, expand, contract outside /
    inside, shrink towards the best; stop on the relative spread test or the exact budget.
    """
    alpha, beta, gamma, sigma = coef
    clip = lambda x: np.minimum(np.maximum(x, lower), upper)
    points = []

    def evaluate(x):
        if len(points) >= budget:
            raise StopIteration
        points.append(np.array(x))
        return f(x)

    simplex = [clip(np.array(v, float)) for v in simplex]
    n = len(simplex) - 1
    try:
        values = [evaluate(v) for v in simplex]
        while True:
            order = np.argsort(values, kind="stable")
            low, high = int(np.argmin(values)), int(np.argmax(values))
            second = max((i for i in range(n + 1) if i != high), key=lambda i: values[i])
            if 2 * abs(values[high] - values[low]) <= ftol * (abs(values[high]) + abs(values[low]) + 1e-12):
                return points
            c = np.mean([simplex[i] for i in range(n + 1) if i != high], axis=0)
            xr = clip(c + alpha * (c - simplex[high]))
            fr = evaluate(xr)
            if fr < values[low]:
                xe = clip(c + alpha * beta * (c - simplex[high]))
                fe = evaluate(xe)
                simplex[high], values[high] = (xe, fe) if fe < fr else (xr, fr)
            elif fr < values[second]:
                simplex[high], values[high] = xr, fr
            else:
                outside = fr < values[high]
                xc = clip(c + alpha * gamma * (c - simplex[high])) if outside else clip(c - gamma * (c - simplex[high]))
                fc = evaluate(xc)
                if (fc <= fr) if outside else (fc < values[high]):
                    simplex[high], values[high] = xc, fc
                else:
                    for i in range(n + 1):
                        if i != low:
                            simplex[i] = clip(simplex[low] + sigma * (simplex[i] - simplex[low]))
                    for i in range(n + 1):
                        if i != low:
                            values[i] = evaluate(simplex[i])
            del order
    except StopIteration:
        return points


# --- costs ---


def naive_non_overlapping_ratio(target, model, n_classes, ignore_unknown=True):
    """Eq. (1) with Python sets of pixel coordinates; empty unions drop out, all empty gives 1.
    With ``ignore_unknown``, model pixels over unknown (255) target pixels are not in B_c. A class
    matched exactly counts ``1 / (union + 1)`` unless every class is (then 0)."""
    terms, exact = [], []
    for c in range(1, n_classes + 1):
        a = set(zip(*np.nonzero(target == c)))
        b = set(zip(*np.nonzero((model == c) & ((target != 255) if ignore_unknown else True))))
        union, inter = len(a | b), len(a & b)
        if union:
            exact.append(union == inter)
            terms.append((union - inter) / union if union != inter else 1.0 / (union + 1))
    if not terms:
        return 1.0
    if all(exact):
        return 0.0
    return float(np.prod(terms) ** (1.0 / len(terms)))


def naive_mean_edge_distance(distance, edges, penalty):
    """Eq. (2) by a plain loop."""
    values = [distance[i, j] for i in range(edges.shape[0]) for j in range(edges.shape[1]) if edges[i, j]]
    return float(sum(values) / len(values)) if values else float(penalty)


def naive_edge_gradient(pose, model, camera, distance, edge_gap, spacing=1.0, h=1e-6):
    """The contour mean of :class:`mocap.cost.EdgeGradient` and its gradient, written plainly:
    posed vertices by :func:`naive_segment_transforms`, facing by cross products, the contour
    edges from a dictionary of edges, visibility from :func:`mocap.render.render`'s edge mask,
    bilinear reads by ``scipy.ndimage.map_coordinates`` of ``np.gradient``'s maps, and each
    sample's dX/dq by central differences of the kinematics (step ``h``), not by joint axes.

    Returns (contour_value, gradient (23,), samples).
    """
    from scipy import ndimage

    from mocap.body.skeleton import SEGMENT_NAMES
    from mocap.render import render

    mesh = model.mesh
    mask = render(pose, model, camera, edge_gap=edge_gap).edges
    gv, gu = np.gradient(np.asarray(distance, np.float64))
    fx, fy, cx, cy = camera.fx, camera.fy, camera.cx, camera.cy

    def posed(q):
        tr = naive_segment_transforms(q, model.skeleton.offsets)
        return np.array([tr[SEGMENT_NAMES[s]][0] @ v + tr[SEGMENT_NAMES[s]][1]
                         for v, s in zip(mesh.vertices, mesh.vertex_segment)])

    pts = posed(pose)
    uv = np.c_[fx * pts[:, 0] / pts[:, 2] + cx, fy * pts[:, 1] / pts[:, 2] + cy]
    owners = {}
    for t, tri in enumerate(mesh.triangles):
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            owners.setdefault((min(a, b), max(a, b)), []).append(t)
    a, b, c = (uv[mesh.triangles[:, i]] for i in range(3))
    front = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1]) < 0
    # sample parameters of every contour edge, and the camera point of a sample for any pose
    samples = []
    for (i, j), (t0, t1) in owners.items():
        if front[t0] == front[t1]:
            continue
        n = max(int(np.ceil(np.linalg.norm(uv[j] - uv[i]) / spacing)), 1)
        samples += [(i, j, (k + 0.5) / n) for k in range(n)]

    def sample_points(q):
        p = posed(q)
        return np.array([(1 - t) * p[i] + t * p[j] for i, j, t in samples])

    x = sample_points(pose)
    u, v = fx * x[:, 0] / x[:, 2] + cx, fy * x[:, 1] / x[:, 2] + cy
    h_img, w_img = mask.shape
    keep = np.zeros(len(u), bool)
    for n, (px, py) in enumerate(zip(np.floor(u).astype(int), np.floor(v).astype(int))):
        if 0 <= px < w_img and 0 <= py < h_img:
            near = [(py, px), (py, px - 1), (py, px + 1), (py - 1, px), (py + 1, px)]
            keep[n] = any(0 <= r < h_img and 0 <= s < w_img and mask[r, s] for r, s in near)
    if not keep.any():
        return float(np.max(distance)), np.zeros(23), 0
    rows, cols = v[keep] - 0.5, u[keep] - 0.5
    read = lambda img: ndimage.map_coordinates(img, [rows, cols], order=1, mode="nearest")
    value = float(read(np.asarray(distance, np.float64)).mean())
    du, dv = read(gu), read(gv)
    grad = np.zeros(23)
    for k in range(23):
        e = np.zeros(23)
        e[k] = h
        xp, xm = sample_points(pose + e)[keep], sample_points(pose - e)[keep]
        dudq = (fx * xp[:, 0] / xp[:, 2] - fx * xm[:, 0] / xm[:, 2]) / (2 * h)
        dvdq = (fy * xp[:, 1] / xp[:, 2] - fy * xm[:, 1] / xm[:, 2]) / (2 * h)
        grad[k] = np.mean(du * dudq + dv * dvdq)
    return value, grad, int(keep.sum())


def naive_region_gradient(pose, model, camera, target, edge_gap, ignore_unknown=True, spacing=1.0, h=1e-6):
    """dF/dq of :class:`mocap.cost.RegionGradient`, written plainly: the render of
    :func:`mocap.render.render` (parts, depth, labels), the contour samples of
    :func:`naive_edge_gradient`'s construction with their outward normal from the front
    triangle's third vertex, seams from array comparisons, every point's motion by central
    differences of :func:`naive_segment_transforms` (step ``h``), target shares by
    ``scipy.ndimage.map_coordinates``, and eq. (1)'s derivative from the class counts.

    Returns (F, gradient (23,), samples).
    """
    from scipy import ndimage

    from mocap.body.skeleton import SEGMENT_NAMES
    from mocap.labels import UNKNOWN
    from mocap.render import render

    mesh, m = model.mesh, model.n_classes
    rendering = render(pose, model, camera, edge_gap=edge_gap)
    parts, depth, labels = rendering.parts.astype(int), rendering.depth.astype(np.float64), rendering.labels
    h_img, w_img = parts.shape
    fx, fy, cx, cy = camera.fx, camera.fy, camera.cx, camera.cy
    target = np.asarray(target)
    part_label = np.asarray(model.part_label, int)
    part_segment = np.zeros(int(mesh.triangle_part.max()) + 1, int)
    part_segment[mesh.triangle_part] = mesh.vertex_segment[mesh.triangles[:, 0]]

    def transforms(q):
        tr = naive_segment_transforms(q, model.skeleton.offsets)
        return [tr[name] for name in SEGMENT_NAMES]

    base = transforms(pose)
    moved = [(transforms(pose + h * e), transforms(pose - h * e)) for e in np.eye(23)]

    def pixel_speed(point, segment, normal):
        """d(normal . uv)/dq of a camera point carried rigidly by ``segment``."""
        r, t = base[segment]
        local = r.T @ (point - t)
        out = np.empty(23)
        for k, (plus, minus) in enumerate(moved):
            uv = []
            for tr in (plus, minus):
                x = tr[segment][0] @ local + tr[segment][1]
                uv.append(np.array([fx * x[0] / x[2], fy * x[1] / x[2]]))
            out[k] = normal @ (uv[0] - uv[1]) / (2 * h)
        return out

    share = lambda image, u, v: float(ndimage.map_coordinates(image.astype(np.float64), [[v - 0.5], [u - 0.5]],
                                                             order=1, mode="nearest")[0])
    d_model, d_overlap = np.zeros((m + 1, 23)), np.zeros((m + 1, 23))

    def add(c_in, c_out, speed, counted, hit_in, hit_out):
        d_model[c_in] += counted * speed
        d_overlap[c_in] += hit_in * speed
        if c_out > 0:
            d_model[c_out] -= counted * speed
            d_overlap[c_out] -= hit_out * speed

    known = (target != UNKNOWN) if ignore_unknown else np.ones(target.shape, bool)
    # occluding contour samples
    pts = np.array([base[s][0] @ v + base[s][1] for v, s in zip(mesh.vertices, mesh.vertex_segment)])
    uv = np.c_[fx * pts[:, 0] / pts[:, 2] + cx, fy * pts[:, 1] / pts[:, 2] + cy]
    a, b, c = (uv[mesh.triangles[:, i]] for i in range(3))
    front = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1]) < 0
    owners = {}
    for t, tri in enumerate(mesh.triangles):
        for i, j in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            owners.setdefault((min(i, j), max(i, j)), []).append(t)
    samples = 0
    for (i, j), (t0, t1) in owners.items():
        if front[t0] == front[t1]:
            continue
        f = t0 if front[t0] else t1
        part = mesh.triangle_part[f]
        c_in = part_label[part]
        w = int(sum(mesh.triangles[f]) - i - j)
        d = uv[j] - uv[i]
        length = np.linalg.norm(d)
        normal = np.array([d[1], -d[0]]) / length
        if normal @ (uv[w] - uv[i]) > 0:
            normal = -normal
        n = max(int(np.ceil(length / spacing)), 1)
        for k in range(n):
            s = (k + 0.5) / n
            x = (1 - s) * pts[i] + s * pts[j]
            u, v = fx * x[0] / x[2] + cx, fy * x[1] / x[2] + cy
            pin, qin = int(np.floor(u - 0.75 * normal[0])), int(np.floor(v - 0.75 * normal[1]))
            pout, qout = int(np.floor(u + 0.75 * normal[0])), int(np.floor(v + 0.75 * normal[1]))
            if not (0 <= pin < w_img and 0 <= qin < h_img) or parts[qin, pin] != part + 1:
                continue
            c_out = 0
            if 0 <= pout < w_img and 0 <= qout < h_img and parts[qout, pout] != 0:
                if depth[qout, pout] < x[2]:
                    continue
                c_out = part_label[parts[qout, pout] - 1]
            if c_out == c_in:
                continue
            samples += 1
            speed = pixel_speed(x, mesh.vertex_segment[i], normal) * (length / n)
            add(c_in, c_out, speed, share(known, u, v), share(target == c_in, u, v),
                share(target == c_out, u, v) if c_out > 0 else 0.0)
    # seams between parts of different classes without an occluding depth step
    for axis, normal in ((1, np.array([1.0, 0.0])), (0, np.array([0.0, 1.0]))):
        pa = parts[:, :-1] if axis == 1 else parts[:-1]
        pb = parts[:, 1:] if axis == 1 else parts[1:]
        for y, x in zip(*np.nonzero((pa > 0) & (pb > 0) & (pa != pb))):
            y2, x2 = (y, x + 1) if axis == 1 else (y + 1, x)
            ca, cb = part_label[parts[y, x] - 1], part_label[parts[y2, x2] - 1]
            za, zb = depth[y, x], depth[y2, x2]
            if ca == cb or abs(1 / za - 1 / zb) > edge_gap / za / zb:
                continue
            samples += 1
            speeds = []
            for (yy, xx), z in (((y, x), za), ((y2, x2), zb)):
                point = np.array([z * (xx + 0.5 - cx) / fx, z * (yy + 0.5 - cy) / fy, z])
                speeds.append(pixel_speed(point, part_segment[parts[yy, xx] - 1], normal))
            pair = [target[y, x], target[y2, x2]]
            counted = np.mean([p != UNKNOWN for p in pair]) if ignore_unknown else 1.0
            add(ca, cb, 0.5 * (speeds[0] + speeds[1]), counted, np.mean([p == ca for p in pair]),
                np.mean([p == cb for p in pair]))
    # eq. (1) and its derivative from the class counts
    value = naive_non_overlapping_ratio(target, labels, m, ignore_unknown)
    grad, used = np.zeros(23), 0
    for cl in range(1, m + 1):
        a_c = np.count_nonzero(target == cl)
        b_c = np.count_nonzero((labels == cl) & known)
        i_c = np.count_nonzero((labels == cl) & (target == cl))
        union = a_c + b_c - i_c
        if union == 0:
            continue
        used += 1
        d_union = d_model[cl] - d_overlap[cl]
        miss = union - i_c
        grad += -d_union / (union + 1.0) if miss == 0 else (d_union - d_overlap[cl]) / miss - d_union / union
    if used == 0 or value == 0.0:
        return value, np.zeros(23), samples
    return value, grad * value / used, samples


def naive_keypoint_distance(pose, model, camera, uv, confidence, scale=None, swap=False):
    """D_k from the model's joints (scipy forward kinematics above) projected by the pinhole
    formula: the confidence-weighted mean over joints with a finite keypoint and positive
    confidence (0 if none) of ``scale * log(1 + d / scale)`` of each keypoint's pixel distance d
    (d itself without ``scale``), the image diagonal for a joint nearer than 5 cm; with ``swap``
    the lower of that and the same with every ``r_`` joint's keypoint given to its ``l_`` twin
    and back. ``confidence`` may carry the silhouette gates already (the weights)."""
    transforms = naive_segment_transforms(pose, model.skeleton.offsets)
    from mocap.body import JOINT_NAMES
    from mocap.body.skeleton import SEGMENT_NAMES

    def projected(name):
        j = JOINT_NAMES.index(name)
        r, t = transforms[SEGMENT_NAMES[model.skeleton.joint_segment[j]]]
        x, y, z = r @ model.skeleton.joint_local[j] + t
        return None if z < 0.05 else np.array([camera.fx * x / z + camera.cx, camera.fy * y / z + camera.cy])

    def total(relabel):
        acc, weight = 0.0, 0.0
        for j, name in enumerate(JOINT_NAMES):
            c = confidence[j]
            if not (c > 0) or not np.all(np.isfinite(uv[j])):
                continue
            p = projected(relabel(name))
            d = np.hypot(camera.width, camera.height) if p is None else float(np.hypot(*(p - uv[j])))
            if scale is not None:
                d = scale[j] * np.log(1.0 + d / scale[j])
            acc += c * d
            weight += c
        return acc / weight if weight else 0.0

    def other_side(name):
        return {"r_": "l_", "l_": "r_"}.get(name[:2], name[:2]) + name[2:]

    direct = total(lambda name: name)
    return min(direct, total(other_side)) if swap else direct


# --- synth ---


def naive_surface_samples(rows, cols, tri, triangles, verts, normals, local, vnoise, cam):
    """Surface attributes per pixel by solving t*ray = v0 + b1*e1 + b2*e2 with numpy.linalg.solve,
    barycentrics clamped into the triangle as the kernel does; returns normal, local, point, noise."""
    fx, fy, cx, cy = cam[:4]
    out = ([], [], [], [])
    for r, c, t in zip(rows, cols, tri):
        i0, i1, i2 = triangles[t]
        ray = np.array([(c + 0.5 - cx) / fx, (r + 0.5 - cy) / fy, 1.0])
        e1, e2 = verts[i1] - verts[i0], verts[i2] - verts[i0]
        _, b1, b2 = np.linalg.solve(np.stack([ray, -e1, -e2], axis=1), verts[i0])
        b1, b2 = min(max(b1, 0.0), 1.0), min(max(b2, 0.0), 1.0)
        if b1 + b2 > 1.0:
            b1, b2 = b1 / (b1 + b2), b2 / (b1 + b2)
        w = np.array([1.0 - b1 - b2, b1, b2])
        n = w @ normals[[i0, i1, i2]]
        out[0].append(n / np.linalg.norm(n))
        out[1].append(w @ local[[i0, i1, i2]])
        out[2].append(w @ verts[[i0, i1, i2]])
        out[3].append(w @ vnoise[[i0, i1, i2]])
    return tuple(np.array(a) for a in out)


# --- imaging ---


def naive_densest_sample(video, radius):
    """Twin of ``imaging.background._densest_sample``: per pixel, the sample with the most
    samples within ``radius`` (NumPy over all pairs; ties to the earlier sample)."""
    data = video.astype(np.float32)
    counts = np.empty(video.shape[:3], np.int32)
    for i in range(len(data)):
        counts[i] = (np.sum((data - data[i]) ** 2, axis=3) <= radius * radius).sum(axis=0)
    best = np.argmax(counts, axis=0)
    return np.take_along_axis(video, best[None, ..., None], axis=0)[0]


def naive_change_mask(frame, background, change_threshold, shadow_min_brightness,
                      shadow_max_brightness, shadow_max_chroma, chroma_noise):
    """Raw background-subtraction test (before clean-up), pixel by pixel in float64 0-255."""
    scale_f = 255.0 if frame.dtype.kind == "f" else 1.0
    scale_b = 255.0 if background.dtype.kind == "f" else 1.0
    out = np.zeros(frame.shape[:2], dtype=bool)
    for y in range(frame.shape[0]):
        for x in range(frame.shape[1]):
            i = frame[y, x].astype(np.float64) * scale_f
            e = background[y, x].astype(np.float64) * scale_b
            if np.linalg.norm(i - e) <= change_threshold:
                continue
            if not e.any():
                out[y, x] = True
                continue
            alpha = i @ e / (e @ e)
            if not shadow_min_brightness <= alpha <= shadow_max_brightness:
                out[y, x] = True
                continue
            allowed = chroma_noise + shadow_max_chroma * alpha * np.linalg.norm(e)
            out[y, x] = np.linalg.norm(i - alpha * e) > allowed
    return out


def naive_hsv(image):
    """HSV by scikit-image, hue in degrees."""
    from skimage.color import rgb2hsv

    hsv = rgb2hsv(image)
    hsv[..., 0] *= 360.0
    return hsv


def naive_classify(image, foreground, means, covariances, threshold, unknown=255):
    """Most likely Gaussian class per pixel (wrapped hue), by explicit loops."""
    hsv = naive_hsv(image)
    out = np.zeros(image.shape[:2], dtype=np.uint8)
    inv = [np.linalg.inv(c) for c in covariances]
    logdet = [np.log(np.linalg.det(c)) for c in covariances]
    for y in range(image.shape[0]):
        for x in range(image.shape[1]):
            if not foreground[y, x]:
                continue
            best, label = -np.inf, unknown
            for c in range(len(means)):
                d = hsv[y, x] - means[c]
                d[0] = (d[0] + 180.0) % 360.0 - 180.0
                d2 = d @ inv[c] @ d
                score = -0.5 * d2 - 0.5 * logdet[c]
                if d2 <= threshold and score > best:
                    best, label = score, c + 1
            out[y, x] = label
    return out


def naive_distance(edges, max_distance, metric="euclidean"):
    """Distance to the nearest edge by brute force over all edge pixels, truncated.

    ``metric="chamfer34"``: Borgefors' 3-4 path length between two pixels,
    ``(4 min(dx, dy) + 3 (max - min)) / 3``.
    """
    pts = np.argwhere(edges)
    out = np.full(edges.shape, float(max_distance))
    for y in range(edges.shape[0]):
        for x in range(edges.shape[1]):
            if len(pts) == 0:
                continue
            dy = np.abs(pts[:, 0] - y)
            dx = np.abs(pts[:, 1] - x)
            if metric == "euclidean":
                d = np.sqrt(dy * dy + dx * dx)
            else:
                lo, hi = np.minimum(dx, dy), np.maximum(dx, dy)
                d = (4 * lo + 3 * (hi - lo)) / 3.0
            out[y, x] = min(d.min(), max_distance)
    return out


def naive_deriche_1d(x, a, b):
    """Deriche causal + anti-causal recursion on a 1-D signal, borders replicated far out."""
    pad = 200
    xp = np.concatenate([np.full(pad, x[0]), x, np.full(pad, x[-1])])
    n = len(xp)
    y1 = np.zeros(n)
    y2 = np.zeros(n)
    for i in range(n):
        y1[i] = a[0] * xp[i] + (a[1] * xp[i - 1] if i >= 1 else a[1] * xp[0])
        y1[i] += (b[0] * y1[i - 1] if i >= 1 else 0.0) + (b[1] * y1[i - 2] if i >= 2 else 0.0)
    for i in range(n - 1, -1, -1):
        x1 = xp[i + 1] if i + 1 < n else xp[-1]
        x2 = xp[i + 2] if i + 2 < n else xp[-1]
        y2[i] = a[2] * x1 + a[3] * x2
        y2[i] += (b[0] * y2[i + 1] if i + 1 < n else 0.0) + (b[1] * y2[i + 2] if i + 2 < n else 0.0)
    return (y1 + y2)[pad:pad + len(x)]


def naive_nonmax_suppression(gy, gx, magnitude, low):
    """Canny's non-maximum suppression: a pixel (not on the border) with magnitude >= ``low`` is
    kept when it is >= the magnitude one step ahead along its gradient and > the one a step behind.

    The step goes to the 3x3 ring (the gradient scaled by 1 / max(|gx|, |gy|)) and is taken
    towards +column when |gx| >= |gy|, else towards +row; the ring's values come from
    ``scipy.ndimage.map_coordinates`` (bilinear). Returns the kept magnitudes, 0 elsewhere.
    """
    from scipy import ndimage

    h, w = magnitude.shape
    out = np.zeros_like(magnitude)
    for r in range(1, h - 1):
        for c in range(1, w - 1):
            m, dy, dx = magnitude[r, c], gy[r, c], gx[r, c]
            if m < low or (dx == 0 and dy == 0):
                continue
            if abs(dx) >= abs(dy):
                step = np.array([dy / dx, 1.0])
            else:
                step = np.array([1.0, dx / dy])
            ahead, behind = ndimage.map_coordinates(magnitude, np.array([[r, c] + step, [r, c] - step]).T, order=1)
            if m >= ahead and m > behind:
                out[r, c] = m
    return out


def naive_hysteresis(strength, high):
    """Pixels with ``strength > 0`` joined (8-neighbour, by flood fill) to one with ``strength >= high``."""
    h, w = strength.shape
    keep = np.zeros((h, w), bool)
    stack = [tuple(p) for p in np.argwhere(strength >= high) if strength[tuple(p)] > 0]
    while stack:
        r, c = stack.pop()
        if keep[r, c]:
            continue
        keep[r, c] = True
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, c + dc
                if 0 <= rr < h and 0 <= cc < w and not keep[rr, cc] and strength[rr, cc] > 0:
                    stack.append((rr, cc))
    return keep


def naive_deriche_edges(gy, gx, gain, low, high):
    """Deriche edges from the gradient: magnitude ``gain * hypot(gy, gx)``, non-maximum
    suppression, hysteresis (the steps of :func:`mocap.imaging.detect_edges` after the gradient)."""
    magnitude = gain * np.hypot(gy, gx)
    return naive_hysteresis(naive_nonmax_suppression(gy, gx, magnitude, low), high)


# --- run ---


def naive_draw_model(frame, labels, edges, n_classes=2, alpha=0.35, class_names=None):
    """Twin of the overlay's compiled drawers (:func:`mocap.imaging.visual.draw_model_box` through
    :class:`mocap.run.overlay.ModelDrawer`, and :func:`mocap.run.overlay.draw_model`, which look at
    the model's box only): the whole frame blended in float32 where labelled, the edges drawn."""
    from mocap.imaging.visual import label_palette
    from mocap.imaging.visual import EDGE_COLOUR

    out = frame.copy()
    model = np.nonzero(labels)
    colours = label_palette(n_classes, class_names)[labels[model]].astype(np.float32)
    blended = (1 - alpha) * frame[model].astype(np.float32) + alpha * colours
    out[model] = np.clip(blended, 0, 255).astype(np.uint8)
    out[edges] = EDGE_COLOUR
    return out


def naive_inset_points(pose, skeleton):
    """The points the depth insets draw (:data:`mocap.imaging.visual.INSET_POINT_NAMES`: the named
    joints, then the chest's base), from :func:`naive_segment_transforms`: shape (11, 3), metres."""
    from mocap.body.skeleton import SEGMENT_NAMES

    transforms = naive_segment_transforms(pose, skeleton.offsets)
    joints = [transforms[SEGMENT_NAMES[s]][0] @ local + transforms[SEGMENT_NAMES[s]][1]
              for s, local in zip(skeleton.joint_segment, skeleton.joint_local)]
    return np.array(joints + [transforms["chest"][1]])


def naive_depth_insets(picture, points, insets):
    """Twin of the overlay's depth insets (:func:`mocap.imaging.visual.draw_inset_points`, through
    :func:`~mocap.imaging.visual.draw_depth_insets` and :class:`~mocap.imaging.visual.ModelDrawer`),
    written from :class:`~mocap.imaging.visual.DepthInsets`' description with whole-array steps:
    the ``points`` (shape (11, 3), metres) drawn in the layout of ``insets`` (boxes, scale,
    thickness) on a copy of ``picture``."""
    from mocap.imaging.visual import (INSET_BONES, INSET_COLOURS, INSET_POINT_NAMES, INSET_SHADE, INSET_SPAN_M,
                                      INSET_TICK_M)

    out = picture.copy()
    neck, head = points[INSET_POINT_NAMES.index("neck")], points[INSET_POINT_NAMES.index("head")]
    t = int(insets.thickness)
    lo, hi = -(t // 2), (t - 1) // 2

    def pixel(view, box, rel):
        """Pixels (x, y) of points ``rel`` metres from the neck: side view z right, y down; top view x right, z up."""
        cx, cy = (box[0] + box[2]) // 2, (box[1] + box[3]) // 2
        a = np.floor(np.asarray(rel, float) * insets.scale + 0.5).astype(np.int64)
        return (cx + a[..., 2], cy + a[..., 1]) if view == 0 else (cx + a[..., 0], cy - a[..., 2])

    def inside(box, x, y):
        return (box[0] <= x) & (x <= box[2]) & (box[1] <= y) & (y <= box[3])

    def squares(box, x, y, low, high, colour):
        x, y = np.atleast_1d(x), np.atleast_1d(y)
        for dy in range(low, high + 1):
            for dx in range(low, high + 1):
                keep = inside(box, x + dx, y + dy)
                out[y[keep] + dy, x[keep] + dx] = colour

    def line(box, start, end, low, high, colour):
        """The line's steps squared; returns its last step inside the box."""
        (x0, y0), (x1, y1) = start, end
        n = max(abs(x1 - x0), abs(y1 - y0))
        k = np.arange(n + 1)
        x = x0 + (2 * (x1 - x0) * k + n) // (2 * n) if n else np.array([x0])
        y = y0 + (2 * (y1 - y0) * k + n) // (2 * n) if n else np.array([y0])
        squares(box, x, y, low, high, colour)
        steps = np.flatnonzero(inside(box, x, y))
        return (x[steps[-1]], y[steps[-1]]) if steps.size else (x0, y0)

    distance = np.linalg.norm(neck)
    for view, box in enumerate(insets.boxes):
        if box[0] > box[2]:
            continue
        region = out[box[1]:box[3] + 1, box[0]:box[2] + 1]
        region[:] = np.clip((1 - INSET_SHADE) * region.astype(np.float32) + INSET_SHADE * np.float32(0), 0,
                            255).astype(np.uint8)
        if distance > 0:
            u = neck / distance
            camera = line(box, pixel(view, box, u * INSET_SPAN_M), pixel(view, box, -(u * INSET_SPAN_M)), 0, 0,
                          INSET_COLOURS[3])
            ticks = np.arange(1, int((distance + INSET_SPAN_M) / INSET_TICK_M) + 1) * INSET_TICK_M
            ticks = ticks[ticks >= distance - INSET_SPAN_M]
            squares(box, *pixel(view, box, (ticks - distance)[:, None] * u), lo - 1, hi + 1, INSET_COLOURS[3])
            squares(box, *camera, -t, t, INSET_COLOURS[4])
        for i, j, colour in INSET_BONES:
            line(box, pixel(view, box, points[i] - neck), pixel(view, box, points[j] - neck), lo, hi,
                 INSET_COLOURS[colour])
        squares(box, *pixel(view, box, head - neck), -t, t, INSET_COLOURS[0])
    return out
