"""Pictures for people: what the image side sees (the ``segment`` command) and the overlay's
drawing (``overlay.mp4``, :mod:`mocap.run.overlay` writes it).

The overlay's drawer is :class:`ModelDrawer`: its compiled kernel :func:`draw_overlay` renders
the body model straight into reused buffers and blends it into the frame in its box, with no
full-size label image (:func:`blend_table` makes its blend equal to NumPy's float32 one, bit
for bit), then draws the two depth insets of :class:`DepthInsets` (the fitted skeleton seen
from the side and from above). The argument checks sit in the wrappers here, beside the kernels.
"""
from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

from mocap._numba import jit
from mocap.body.kinematics import apply_transforms_into
from mocap.body.pose import check_pose
from mocap.body.skeleton import JOINT_INDEX
from mocap.labels import UNKNOWN
from mocap.render.camera import Camera
from mocap.render.rasterize import (EDGE_DEPTH_GAP_M, Buffers, Scene, clear_render, occluding_edges_into,
                                    render_scene_into)

__all__ = ["EDGE_COLOUR", "INSET_BONES", "INSET_COLOURS", "INSET_FRACTION", "INSET_SPAN_M", "INSET_TICK_M",
           "DepthInsets", "ModelDrawer", "blend_into_box", "blend_table", "colour_distance", "colour_labels",
           "draw_depth_insets", "draw_model", "draw_model_box", "draw_overlay", "label_palette",
           "overlay_edges", "tile"]

#: Colours of the named classes (others: tab10).
CLASS_COLOURS = {"skin": (255, 196, 150), "clothes": (40, 110, 255), "hair": (120, 60, 20),
                 "lower_body": (40, 170, 110)}
_FIRST_COLOURS = np.array([(255, 196, 150), (40, 110, 255)], dtype=np.uint8)  # skin, clothes


def _tab10() -> np.ndarray:
    """matplotlib's tab10 colours, uint8 RGB, shape (10, 3) (matplotlib imported when needed)."""
    from matplotlib import colormaps

    return (np.array(colormaps["tab10"].colors) * 255).round().astype(np.uint8)


def label_palette(n_classes: int, class_names: tuple[str, ...] | None = None) -> np.ndarray:
    """RGB colour of every label value: 0 black, 255 grey; classes by name
    (:data:`CLASS_COLOURS`: skin tone, blue clothes, brown hair, green lower body) when
    ``class_names`` are given, else 1 skin tone, 2 blue, then tab10.

    Returns
    -------
    ndarray of uint8, shape (256, 3)
    """
    palette = np.zeros((256, 3), dtype=np.uint8)
    if class_names is not None and len(class_names) != n_classes:
        raise ValueError(f"need {n_classes} class names, got {class_names}")
    for c in range(1, n_classes + 1):
        if class_names is not None and class_names[c - 1] in CLASS_COLOURS:
            palette[c] = CLASS_COLOURS[class_names[c - 1]]
        else:
            palette[c] = _FIRST_COLOURS[c - 1] if c <= 2 else _tab10()[(c - 3) % 10]
    palette[UNKNOWN] = (150, 150, 150)
    return palette


def colour_labels(labels: np.ndarray, n_classes: int, class_names: tuple[str, ...] | None = None) -> np.ndarray:
    """Label image (uint8, shape (H, W)) as RGB (uint8, shape (H, W, 3)) with
    :func:`label_palette`."""
    return label_palette(n_classes, class_names)[labels]


def colour_distance(distance: np.ndarray, max_distance: float) -> np.ndarray:
    """Distance map (pixels, shape (H, W)) as RGB (uint8, (H, W, 3)) with viridis:
    dark on edges, yellow at ``max_distance``."""
    from matplotlib import colormaps     # imported when drawn: matplotlib takes ~0.1 s to import

    lut = (colormaps["viridis"](np.linspace(0, 1, 256))[:, :3] * 255).round().astype(np.uint8)
    index = np.clip(distance / max_distance * 255.0, 0, 255).astype(np.uint8)
    return lut[index]


def overlay_edges(frame: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The frame (uint8 RGB) darkened and greyed, with the edge pixels in white."""
    grey = (frame.astype(np.float32).mean(axis=2) * 0.4).astype(np.uint8)
    out = np.repeat(grey[..., np.newaxis], 3, axis=2)
    out[edges] = 255
    return out


def tile(images: list[np.ndarray], columns: int = 2) -> np.ndarray:
    """Same-size uint8 RGB images in a grid, row by row (missing cells black)."""
    h, w = images[0].shape[:2]
    rows = -(-len(images) // columns)
    out = np.zeros((rows * h, columns * w, 3), dtype=np.uint8)
    for i, image in enumerate(images):
        r, c = divmod(i, columns)
        out[r * h:(r + 1) * h, c * w:(c + 1) * w] = image
    return out


@functools.lru_cache(maxsize=8)
def blend_table(alpha: float) -> np.ndarray:
    """``table[f, c]``: a frame value ``f`` with a colour value ``c`` blended at opacity ``alpha``,
    as NumPy computes it in float32 (``(1 - alpha) * f + alpha * c``, clipped to 0-255 and cut
    to uint8): the compiled drawers look it up, so their pictures equal NumPy's bit for bit.

    Returns
    -------
    ndarray of uint8, shape (256, 256), read-only
    """
    if not 0.0 <= alpha <= 1.0:
        raise ValueError(f"alpha must be in [0, 1], got {alpha}")
    values = np.arange(256, dtype=np.float32)
    table = np.clip((1 - alpha) * values[:, None] + alpha * values[None, :], 0, 255).astype(np.uint8)
    table.setflags(write=False)
    return table


@jit
def blend_into_box(out, frame, ids, lut, marks, width, box, palette, table, edge_colour):
    """Compiled: in the inclusive pixel ``box`` (int64 (4,): x0, y0, x1, y1), the pixels of the
    flat ``ids`` (uint8, (H * W,)) whose label ``lut[id]`` is not 0 get ``frame`` blended with
    ``palette[label]`` by ``table`` (:func:`blend_table`), and those marked in the flat bool
    ``marks`` get ``edge_colour``; ``out`` and ``frame`` are uint8 (H, W, 3) (the same array
    may be both). Other pixels are not touched."""
    for y in range(box[1], box[3] + 1):
        row = y * width
        for x in range(box[0], box[2] + 1):
            i = row + x
            if marks[i]:
                out[y, x, 0] = edge_colour[0]
                out[y, x, 1] = edge_colour[1]
                out[y, x, 2] = edge_colour[2]
                continue
            label = lut[ids[i]]
            if label != 0:
                for c in range(3):
                    out[y, x, c] = table[frame[y, x, c], palette[label, c]]


@jit
def draw_model_box(out, pose, scene, buffers, marks, lut, min_gap, palette, table, edge_colour):
    """Compiled: the body model of ``scene`` (:class:`mocap.render.rasterize.Scene`) in ``pose``
    (float64 (23,), checked) rendered into ``buffers`` (:class:`mocap.render.rasterize.Buffers`,
    zero) with its occluding edges (depth gap ``min_gap``, metres) marked in the flat bool
    ``marks`` (all False), and drawn into the uint8 (H, W, 3) picture ``out`` in place by
    :func:`blend_into_box` (``lut``: uint8 (256,), the label of each part id, 0 for 0); the
    buffers and marks are cleared behind it."""
    render_scene_into(pose, scene, buffers)
    if buffers.box[0] > buffers.box[2]:
        return
    occluding_edges_into(scene, buffers, min_gap, marks)
    blend_into_box(out, out, buffers.part_ids, lut, marks, scene.width, buffers.box, palette, table, edge_colour)
    clear_render(scene, buffers, marks)


# --- the overlay's drawer: the model in its box, then the depth insets ---

#: RGB colour of the model's occluding edges.
EDGE_COLOUR = np.array([255, 255, 0], np.uint8)
#: Side of each depth inset, a fraction of the picture's height (120 pixels at 640x480).
INSET_FRACTION = 0.25
#: Smallest inset drawn, pixels (a picture under 96 pixels high has none).
INSET_MIN_SIDE = 24
#: Metres across an inset, a fixed scale (75 pixels a metre at 640x480); the neck at its centre.
INSET_SPAN_M = 1.6
#: Distance between the dots on the line of sight, metres from the camera.
INSET_TICK_M = 0.5
#: Opacity of the black laid over the frame behind an inset.
INSET_SHADE = 0.75
#: RGB colours of the insets, by row: spine and head, right arm, left arm, line of sight and its
#: dots, the camera.
INSET_COLOURS = np.array([(235, 235, 235), (255, 140, 40), (70, 170, 255), (150, 150, 150), (255, 255, 0)], np.uint8)
INSET_COLOURS.setflags(write=False)
#: Points of the insets' skeleton: the named joints, then the chest's base (the root).
INSET_POINT_NAMES: tuple[str, ...] = tuple(JOINT_INDEX) + ("chest_base",)
#: Bones of the insets, drawn in this order: (first point, second point, colour row), points
#: indexing :data:`INSET_POINT_NAMES`, colours :data:`INSET_COLOURS`.
INSET_BONES = np.array([(INSET_POINT_NAMES.index(a), INSET_POINT_NAMES.index(b), colour) for a, b, colour in (
    ("chest_base", "neck", 0), ("neck", "head", 0),
    ("neck", "r_shoulder", 1), ("r_shoulder", "r_elbow", 1), ("r_elbow", "r_wrist", 1), ("r_wrist", "r_hand", 1),
    ("neck", "l_shoulder", 2), ("l_shoulder", "l_elbow", 2), ("l_elbow", "l_wrist", 2), ("l_wrist", "l_hand", 2))],
    np.int64)
INSET_BONES.setflags(write=False)
_NECK, _HEAD, _CHEST_BASE = JOINT_INDEX["neck"], JOINT_INDEX["head"], len(JOINT_INDEX)
_SIDE_VIEW = 0


class DepthInsets(NamedTuple):
    """Where and how the overlay's two depth insets are drawn (a named tuple Numba compiles).

    Two square insets at the picture's right edge, the frame shaded behind them: above, the
    fitted skeleton seen from the side (from the person's left: depth z to the right, the camera
    to the left, down y down); below, seen from above (x to the right as in the frame, depth z
    up, the camera at the bottom). Both at one fixed scale, the neck at the centre, with the line
    of sight through the neck, a dot on it every :data:`INSET_TICK_M` metres from the camera
    (they slide as the fitted depth changes) and the camera marked where it leaves the inset.

    Attributes
    ----------
    joint_segment : ndarray, shape (10,), int64
        :attr:`~mocap.body.kinematics.Skeleton.joint_segment`.
    joint_local : ndarray, shape (10, 3), float64, metres
        :attr:`~mocap.body.kinematics.Skeleton.joint_local`.
    boxes : ndarray, shape (2, 4), int64
        Inclusive pixel box (x0, y0, x1, y1) of the side view and of the top view (x0 > x1:
        none: the picture is too small).
    scale : float64
        Pixels per metre.
    thickness : int64
        Width of the bones, pixels.
    shade : ndarray, shape (256,), uint8
        A frame value with black laid over it at opacity :data:`INSET_SHADE` (:func:`blend_table`).
    colours : ndarray, shape (5, 3), uint8
        :data:`INSET_COLOURS`.
    bones : ndarray, shape (10, 3), int64
        :data:`INSET_BONES`.
    points : ndarray, shape (11, 3), float64, metres
        Scratch: the points of :data:`INSET_POINT_NAMES` of the pose drawn last, camera coordinates.
    """

    joint_segment: np.ndarray
    joint_local: np.ndarray
    boxes: np.ndarray
    scale: float
    thickness: np.int64
    shade: np.ndarray
    colours: np.ndarray
    bones: np.ndarray
    points: np.ndarray

    @classmethod
    def of(cls, skeleton, width: int, height: int) -> "DepthInsets":
        """The insets of a ``width`` x ``height`` picture (pixels) for ``skeleton``
        (:class:`~mocap.body.kinematics.Skeleton`): each ``round(INSET_FRACTION * height)``
        pixels square, 1/30 of that from the edges and apart; none where they would be smaller
        than :data:`INSET_MIN_SIDE` or do not fit."""
        side = int(round(INSET_FRACTION * height))
        margin = max(2, side // 30)
        boxes = np.array([(0, 0, -1, -1), (0, 0, -1, -1)], np.int64)
        if side >= INSET_MIN_SIDE and width >= side + 2 * margin and height >= 2 * side + 3 * margin:
            x0 = width - margin - side
            for view in range(2):
                y0 = margin + view * (side + margin)
                boxes[view] = (x0, y0, x0 + side - 1, y0 + side - 1)
        return cls(skeleton.joint_segment, skeleton.joint_local, boxes, side / INSET_SPAN_M,
                   np.int64(max(1, round(side / 45))), np.ascontiguousarray(blend_table(INSET_SHADE)[:, 0]),
                   INSET_COLOURS, INSET_BONES, np.zeros((len(INSET_POINT_NAMES), 3)))


@jit
def _square(out, box, x, y, lo, hi, colour):
    """Compiled: pixels ``x + lo .. x + hi`` by ``y + lo .. y + hi`` of ``out`` set to ``colour``,
    those inside the inclusive ``box`` only."""
    for yy in range(max(y + lo, box[1]), min(y + hi, box[3]) + 1):
        for xx in range(max(x + lo, box[0]), min(x + hi, box[2]) + 1):
            out[yy, xx, 0] = colour[0]
            out[yy, xx, 1] = colour[1]
            out[yy, xx, 2] = colour[2]


@jit
def _line(out, box, x0, y0, x1, y1, lo, hi, colour):
    """Compiled: the line from pixel (x0, y0) to (x1, y1), one step per pixel of its longer side
    (step k of n at ``x0 + floor((x1 - x0) * k / n + 1/2)``, the same for y), each step a
    :func:`_square` of ``lo .. hi``, clipped to ``box``. Returns the last step inside ``box``
    ((x0, y0) if none)."""
    n = max(abs(x1 - x0), abs(y1 - y0))
    last_x, last_y = x0, y0
    for k in range(n + 1):
        x, y = x0, y0
        if n > 0:
            x = x0 + (2 * (x1 - x0) * k + n) // (2 * n)
            y = y0 + (2 * (y1 - y0) * k + n) // (2 * n)
        _square(out, box, x, y, lo, hi, colour)
        if box[0] <= x <= box[2] and box[1] <= y <= box[3]:
            last_x, last_y = x, y
    return last_x, last_y


@jit
def _inset_pixel(view, box, scale, dx, dy, dz):
    """Compiled: the pixel (x, y) of an inset where a point ``(dx, dy, dz)`` metres from the
    neck lands: the side view puts z right and y down, the top view x right and z up, about the
    box's centre ``((x0 + x1) // 2, (y0 + y1) // 2)``, ``floor(metres * scale + 1/2)`` pixels."""
    cx, cy = (box[0] + box[2]) // 2, (box[1] + box[3]) // 2
    if view == _SIDE_VIEW:
        return cx + int(np.floor(dz * scale + 0.5)), cy + int(np.floor(dy * scale + 0.5))
    return cx + int(np.floor(dx * scale + 0.5)), cy - int(np.floor(dz * scale + 0.5))


@jit
def draw_inset_points(out, insets):
    """Compiled: the two insets of ``insets`` (:class:`DepthInsets`) drawn into the uint8
    (H, W, 3) picture ``out`` for the points in ``insets.points`` (camera coordinates, metres),
    in this order: the frame shaded, the line of sight through the neck (one pixel wide), its
    dots (``thickness + 2`` pixels), the camera (``2 * thickness + 1``), the bones in
    :data:`INSET_BONES` order (``thickness``), the head (``2 * thickness + 1``)."""
    points, scale, t = insets.points, insets.scale, insets.thickness
    lo, hi = -(t // 2), (t - 1) // 2
    cx, cy, cz = points[_NECK, 0], points[_NECK, 1], points[_NECK, 2]
    distance = np.sqrt(cx * cx + cy * cy + cz * cz)
    for view in range(2):
        box = insets.boxes[view]
        if box[0] > box[2]:
            continue
        for y in range(box[1], box[3] + 1):
            for x in range(box[0], box[2] + 1):
                for c in range(3):
                    out[y, x, c] = insets.shade[out[y, x, c]]
        if distance > 0.0:
            ux, uy, uz = cx / distance, cy / distance, cz / distance      # away from the camera
            reach = INSET_SPAN_M
            far_x, far_y = _inset_pixel(view, box, scale, ux * reach, uy * reach, uz * reach)
            near_x, near_y = _inset_pixel(view, box, scale, -(ux * reach), -(uy * reach), -(uz * reach))
            camera_x, camera_y = _line(out, box, far_x, far_y, near_x, near_y, 0, 0, insets.colours[3])
            first = max(1, int(np.ceil((distance - reach) / INSET_TICK_M)))
            for k in range(first, int(np.floor((distance + reach) / INSET_TICK_M)) + 1):
                off = k * INSET_TICK_M - distance
                x, y = _inset_pixel(view, box, scale, off * ux, off * uy, off * uz)
                _square(out, box, x, y, lo - 1, hi + 1, insets.colours[3])
            _square(out, box, camera_x, camera_y, -t, t, insets.colours[4])
        for b in range(insets.bones.shape[0]):
            i, j = insets.bones[b, 0], insets.bones[b, 1]
            x0, y0 = _inset_pixel(view, box, scale, points[i, 0] - cx, points[i, 1] - cy, points[i, 2] - cz)
            x1, y1 = _inset_pixel(view, box, scale, points[j, 0] - cx, points[j, 1] - cy, points[j, 2] - cz)
            _line(out, box, x0, y0, x1, y1, lo, hi, insets.colours[insets.bones[b, 2]])
        x, y = _inset_pixel(view, box, scale, points[_HEAD, 0] - cx, points[_HEAD, 1] - cy, points[_HEAD, 2] - cz)
        _square(out, box, x, y, -t, t, insets.colours[0])


@jit
def draw_depth_insets(out, transforms, insets):
    """Compiled: the points of the pose whose segment ``transforms`` (float64 (8, 3, 4)) are
    given put in ``insets.points`` (the named joints, then the chest's base), and the insets
    drawn by :func:`draw_inset_points`."""
    points = insets.points
    apply_transforms_into(transforms, insets.joint_segment, insets.joint_local, points)
    for c in range(3):
        points[_CHEST_BASE, c] = transforms[0, c, 3]
    draw_inset_points(out, insets)


@jit
def draw_overlay(out, pose, scene, buffers, marks, lut, min_gap, palette, table, edge_colour, insets):
    """Compiled: one overlay picture drawn into ``out`` in place: the model by
    :func:`draw_model_box` (same arguments), then the depth insets of ``insets``
    (:class:`DepthInsets`) by :func:`draw_depth_insets`."""
    draw_model_box(out, pose, scene, buffers, marks, lut, min_gap, palette, table, edge_colour)
    draw_depth_insets(out, buffers.transforms, insets)


def draw_model(frame: np.ndarray, labels: np.ndarray, edges: np.ndarray, n_classes: int = 2, *,
               alpha: float = 0.35, class_names: tuple[str, ...] | None = None) -> np.ndarray:
    """The frame with the model's coloured silhouette blended in and its occluding edges drawn
    (compiled, in the model's box: :func:`blend_into_box`).

    Parameters
    ----------
    frame : ndarray, shape (H, W, 3), uint8
    labels : ndarray, shape (H, W), uint8
        Rendered class labels (colours of :func:`label_palette`).
    edges : ndarray, shape (H, W), bool
        Rendered occluding edges (yellow).
    n_classes : int
    alpha : float
        Opacity of the silhouette colours.
    class_names : tuple of str, optional
        The ``n_classes`` class names, for the colours of named classes (hair, lower body).

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
    """
    if frame.ndim != 3 or frame.shape[:2] != labels.shape or labels.shape != edges.shape:
        raise ValueError(f"frame {frame.shape}, labels {labels.shape} and edges {edges.shape} must match")
    out = np.array(frame, dtype=np.uint8, order="C")
    # only the model's box is looked at: at the input's resolution it is a small part of the frame
    rows = np.flatnonzero(labels.any(axis=1) | edges.any(axis=1))
    if rows.size == 0:
        return out
    cols = np.flatnonzero(labels[rows[0]:rows[-1] + 1].any(axis=0) | edges[rows[0]:rows[-1] + 1].any(axis=0))
    box = np.array([cols[0], rows[0], cols[-1], rows[-1]], np.int64)
    blend_into_box(out, out, np.ascontiguousarray(labels, np.uint8).ravel(), _IDENTITY,
                   np.ascontiguousarray(edges, np.bool_).ravel(), labels.shape[1], box,
                   label_palette(n_classes, class_names), blend_table(alpha), EDGE_COLOUR)
    return out


#: Label of each label value (:func:`draw_model` draws label images, not part ids).
_IDENTITY = np.arange(256, dtype=np.uint8)


class ModelDrawer:
    """The overlay's drawer for one body model and camera: the model in a pose rendered into
    buffers of its own (reused from frame to frame) and drawn into the frame in its box — the
    picture of :func:`draw_model` on :func:`mocap.render.render`'s labels and edges, bit for
    bit — then the fitted skeleton in the two depth insets of :class:`DepthInsets`, all by the
    compiled :func:`draw_overlay`.

    Parameters
    ----------
    model : BodyModel
    camera : Camera
        At the frames' size.
    alpha : float
        Opacity of the silhouette colours.
    """

    def __init__(self, model, camera: Camera, *, alpha: float = 0.35) -> None:
        self.model, self.camera = model, camera
        self.scene, self.buffers = Scene.of(model, camera), Buffers.of(model, camera)
        self.marks = np.zeros(camera.width * camera.height, np.bool_)
        self.lut = np.zeros(256, np.uint8)          # part id (part + 1) -> label; 0 background
        self.lut[1:len(model.part_label) + 1] = model.part_label
        self.palette = label_palette(model.n_classes, model.class_names)
        self.table = blend_table(alpha)
        self.insets = DepthInsets.of(model.skeleton, camera.width, camera.height)

    def draw(self, frame: np.ndarray, pose: np.ndarray) -> np.ndarray:
        """``frame`` (uint8 RGB, shape (h, w, 3), the camera's size; not changed) with the model in
        ``pose`` (shape (23,), radians and metres) and the depth insets drawn: a new array."""
        if frame.shape != (self.camera.height, self.camera.width, 3) or frame.dtype != np.uint8:
            raise ValueError(f"the frame must be uint8 ({self.camera.height}, {self.camera.width}, 3), got "
                             f"{frame.dtype} {frame.shape}")
        out = np.array(frame, order="C")
        draw_overlay(out, check_pose(pose), self.scene, self.buffers, self.marks, self.lut, EDGE_DEPTH_GAP_M,
                     self.palette, self.table, EDGE_COLOUR, self.insets)
        return out

