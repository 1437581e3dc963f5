import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from mocap.body import JOINT_LIMITS, PARAMETER_INDEX as P, PART_NAMES, BodyModel, neutral_pose
from mocap.body.mesh import part_mesh
from mocap.render import Camera, rasterize_mesh, render
from mocap.render.reference import reference_occluding_edges, reference_rasterize

MODEL = BodyModel.build()
CAMERA = Camera.default()
#: Pixels on which the compiled and reference rasterizers may differ (float32 vs float64 depth ties).
BOUNDARY_PIXELS = 3


def random_pose(rng):
    q = rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
    q[:3] = rng.uniform([-0.3, 0.0, 1.5], [0.3, 0.4, 2.5])
    q[P["chest_pitch"]] = rng.uniform(-0.3, 0.3)
    return q


def sphere(radius, centre, resolution=64):
    v, t = part_mesh(2 * radius, 2 * radius, 2 * radius, e_long=1.0, e_cross=1.0, taper=0.0,
                     resolution=resolution, start=-radius)
    return v + np.asarray(centre), t


@pytest.mark.parametrize("seed", range(8))
def test_matches_reference_rasterizer_on_random_poses(seed):
    q = random_pose(np.random.default_rng(seed))
    got = render(q, MODEL, CAMERA)
    parts, inv_depth = reference_rasterize(MODEL.posed_vertices(q), MODEL.mesh.triangles,
                                           MODEL.mesh.triangle_part, CAMERA)
    assert np.count_nonzero(got.parts != parts) <= BOUNDARY_PIXELS
    lut = np.r_[0, MODEL.part_label]
    assert np.count_nonzero(got.labels != lut[parts]) <= BOUNDARY_PIXELS
    visible = parts > 0
    np.testing.assert_allclose(got.depth[visible & (got.parts == parts)],
                               1.0 / inv_depth[visible & (got.parts == parts)], rtol=1e-5)
    assert np.all(np.isinf(got.depth[got.parts == 0]))


@pytest.mark.parametrize("seed", range(8))
def test_occluding_edges_follow_their_definition(seed):
    q = random_pose(np.random.default_rng(100 + seed))
    got = render(q, MODEL, CAMERA, edge_gap=0.03)
    inv = np.where(np.isfinite(got.depth), 1.0 / got.depth.astype(np.float64), 0.0)
    np.testing.assert_array_equal(got.edges, reference_occluding_edges(got.parts, inv, 0.03))


@pytest.mark.parametrize("root_x", [-0.9, -0.55, 0.55, 0.9])
@pytest.mark.parametrize("width", [160, 168, 163])
def test_occluding_edges_at_the_image_border_and_inside_a_word(root_x, width):
    # the model cut by the left or right border, at widths that are and are not a multiple of
    # 8 (the scan's 8-pixel words, whose first and last are partly outside the model's box)
    cam = Camera.default(width, 120)
    q = neutral_pose()
    q[:3] = [root_x, 0.1, 2.0]
    q[P["l_shoulder_abd"]] = 1.2
    got = render(q, MODEL, cam, edge_gap=0.03)
    assert got.edges.any()
    inv = np.where(np.isfinite(got.depth), 1.0 / got.depth.astype(np.float64), 0.0)
    np.testing.assert_array_equal(got.edges, reference_occluding_edges(got.parts, inv, 0.03))


def test_sphere_area_matches_analytic_at_640x480():
    cam = Camera.default(640, 480)
    r, d = 0.25, 2.0
    v, t = sphere(r, (0.0, 0.0, d), resolution=128)
    out = rasterize_mesh(v, t, cam)
    rho = cam.fx * r / np.sqrt(d * d - r * r)    # silhouette of a sphere on the optical axis
    assert np.count_nonzero(out.labels) == pytest.approx(np.pi * rho**2, rel=0.01)


def test_box_face_area_is_exact_with_centres_on_edges():
    # a 200 x 120 pixel rectangle whose sides pass through pixel centres: the top-left rule
    # takes the left and top sides, leaves the right and bottom ones
    cam = Camera(640, 480, 500.0, 500.0, 320.0, 240.0)
    z = 2.0
    u0, u1, v0, v1 = 100.5, 300.5, 50.5, 170.5
    corners = np.array([[(u - 320.0) * z / 500.0, (v - 240.0) * z / 500.0, z]
                        for u, v in ((u0, v0), (u1, v0), (u1, v1), (u0, v1))])
    tris = np.array([[0, 2, 1], [0, 3, 2]])           # both facing the camera
    out, cover = rasterize_mesh(corners, tris, cam, return_coverage=True)
    assert np.count_nonzero(out.labels) == 200 * 120
    assert cover.max() == 1                            # the shared diagonal is drawn once
    rows, cols = np.nonzero(out.labels)
    assert (rows.min(), rows.max(), cols.min(), cols.max()) == (50, 169, 100, 299)


def test_tiled_surface_has_no_cracks_and_no_double_pixels():
    # a 7x5 grid of jittered vertices, two triangles per cell, both orientations mixed
    rng = np.random.default_rng(0)
    cam = Camera(160, 120, 100.0, 100.0, 80.0, 60.0)
    gx, gy = np.meshgrid(np.linspace(-0.5, 0.5, 7), np.linspace(-0.4, 0.4, 5))
    jitter = rng.uniform(-0.04, 0.04, size=gx.shape + (2,))
    jitter[[0, -1], :, 1] = 0.0
    jitter[:, [0, -1], 0] = 0.0
    xy = np.stack([gx, gy], -1) + jitter
    verts = np.concatenate([xy.reshape(-1, 2), np.full((xy.size // 2, 1), 1.0)], axis=1)
    tris = []
    for i in range(4):
        for j in range(6):
            a, b, c, d = i * 7 + j, i * 7 + j + 1, (i + 1) * 7 + j, (i + 1) * 7 + j + 1
            tris += [[a, b, d], [a, d, c]] if (i + j) % 2 else [[a, d, b], [a, c, d]]
    out, cover = rasterize_mesh(verts, np.array(tris), cam, cull=False, return_coverage=True)
    inside = (cover > 0)
    assert cover.max() == 1
    # the union is the outer rectangle: every pixel centre strictly inside it is covered
    u = cam.fx * verts[:, 0] + cam.cx
    v = cam.fy * verts[:, 1] + cam.cy
    cols = np.arange(160) + 0.5
    rows = np.arange(120) + 0.5
    expect = ((rows[:, None] > v.min()) & (rows[:, None] < v.max()) & (cols[None] > u.min()) & (cols[None] < u.max()))
    np.testing.assert_array_equal(inside, expect)


def test_closed_mesh_covered_exactly_twice_without_culling():
    cam = Camera.default(320, 240)
    v, t = sphere(0.3, (0.05, -0.03, 2.0), resolution=24)
    culled = rasterize_mesh(v, t, cam)
    both, cover = rasterize_mesh(v, t, cam, cull=False, return_coverage=True)
    assert set(np.unique(cover)) <= {0, 2}
    np.testing.assert_array_equal(cover == 2, culled.labels > 0)
    np.testing.assert_array_equal(both.labels, culled.labels)   # back faces never win the depth test


def test_cylinder_from_the_side_has_exactly_its_two_outlines():
    # a long horizontal cylinder crossing the whole image: its occluding edges are its top and
    # bottom outlines, and nothing else (the image border is not an edge)
    cam = Camera.default(160, 120)
    v, t = part_mesh(6.0, 0.3, 0.3, e_long=0.05, e_cross=1.0, taper=0.0, resolution=48, start=-3.0)
    v = v[:, [1, 0, 2]] + [0.0, 0.1, 2.0]      # long axis along x
    t = t[:, ::-1]                              # swapping two axes mirrors: keep outward winding
    out = rasterize_mesh(v, t, cam)
    band = out.labels > 0
    cols_with_band = band.any(axis=0)
    assert cols_with_band.all()
    top = band.argmax(axis=0)
    bottom = band.shape[0] - 1 - band[::-1].argmax(axis=0)
    expect = np.zeros_like(band)
    expect[top, np.arange(band.shape[1])] = True
    expect[bottom, np.arange(band.shape[1])] = True
    np.testing.assert_array_equal(out.edges, expect)


def test_arm_across_chest_gives_an_internal_contour_but_creases_do_not():
    q = neutral_pose()
    q[P["r_shoulder_flex"]] = np.deg2rad(40)
    q[P["r_shoulder_abd"]] = np.deg2rad(-25)
    q[P["r_elbow_flex"]] = np.deg2rad(110)
    q[P["r_shoulder_rot"]] = np.deg2rad(-60)
    out = render(q, MODEL, CAMERA)
    parts = out.parts
    # silhouette outline: model pixels with a background 4-neighbour
    bg = np.pad(parts == 0, 1, constant_values=False)
    touches_bg = bg[:-2, 1:-1] | bg[2:, 1:-1] | bg[1:-1, :-2] | bg[1:-1, 2:]
    internal = out.edges & ~touches_bg
    arm = np.isin(parts, [PART_NAMES.index(p) + 1 for p in ("r_forearm", "r_hand")])
    assert np.count_nonzero(internal & arm) >= 5
    # the torso right behind the forearm is not an edge pixel (the nearer side is marked)
    torso = parts == PART_NAMES.index("torso") + 1
    assert not np.any(internal & torso & np.roll(arm, 1, axis=1) & np.roll(arm, -1, axis=1))
    # where neck and head meet, depth is continuous: no contour between them
    neck, head = (parts == PART_NAMES.index(n) + 1 for n in ("neck", "head"))
    head_below = np.zeros_like(head)
    head_below[:-1] = head[1:]
    assert not np.any(out.edges & neck & head_below & ~touches_bg)


def random_triangle(rng, cam):
    """One triangle in camera coordinates at z = 1, of a random kind that stresses the run
    ends: vertices on pixel centres or on a 1/16-pixel grid, horizontal or vertical edges,
    one-row slivers, or coordinates far outside the image (up to 1e5 pixels)."""
    kind = rng.integers(5)
    if kind == 0:                                   # vertices on pixel centres
        uv = rng.integers(-3, 24, (3, 2)) + 0.5
    elif kind == 1:                                 # 1/16-pixel grid, small
        uv = rng.integers(-40, 400, (3, 2)) / 16.0
    elif kind == 2:                                 # a horizontal edge
        uv = rng.uniform(-5, 25, (3, 2))
        uv[1, 1] = uv[0, 1]
    elif kind == 3:                                 # thinner than a row
        uv = rng.uniform(-5, 25, (3, 2))
        uv[:, 1] = rng.uniform(9.3, 10.7) + rng.uniform(0, 0.4, 3)
    else:                                           # huge, crossing the image
        uv = rng.uniform(-1e5, 1e5, (3, 2))
    xy = (uv - [cam.cx, cam.cy]) / [cam.fx, cam.fy]
    return np.concatenate([xy, np.ones((3, 1))], axis=1)


@pytest.mark.parametrize("seed", range(4))
def test_fill_rule_matches_the_per_pixel_edge_test_exactly(seed):
    # each triangle alone: the run ends (and the narrow-box path) must give exactly the
    # pixels of the reference's per-pixel edge test, in both orientations
    rng = np.random.default_rng(seed)
    cam = Camera(20, 20, 10.0, 10.0, 10.0, 10.0)
    tri = np.array([[0, 1, 2]])
    for _ in range(150):
        v = random_triangle(rng, cam)
        for t in (tri, tri[:, ::-1]):
            expect = reference_rasterize(v, t, np.zeros(1, np.int64), cam, cull=False)[0]
            fast = rasterize_mesh(v, t, cam, cull=False)
            runs, cover = rasterize_mesh(v, t, cam, cull=False, triangle_ids=True, return_coverage=True)
            np.testing.assert_array_equal(fast.parts, expect)
            np.testing.assert_array_equal(runs.parts, expect)
            np.testing.assert_array_equal(cover, expect)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 64), st.integers(1, 64))
def test_any_pose_and_size_renders_without_crashing(seed, w, h):
    rng = np.random.default_rng(seed)
    q = rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])   # includes poses behind the camera
    q[:3] = rng.uniform(-3, 3, size=3)
    out = render(q, MODEL, Camera.default(w, h))
    assert out.labels.shape == (h, w) and out.labels.dtype == np.uint8
    assert set(np.unique(out.labels)) <= set(range(MODEL.n_classes + 1))


@pytest.mark.parametrize("call, match", [
    (lambda: rasterize_mesh(np.zeros((3, 2)), [[0, 1, 2]], CAMERA), "vertices"),
    (lambda: rasterize_mesh(np.full((3, 3), np.nan), [[0, 1, 2]], CAMERA), "finite"),
    (lambda: rasterize_mesh(np.ones((3, 3)), [[0, 1, 3]], CAMERA), "out of range"),
    (lambda: rasterize_mesh(np.ones((3, 3)), [[0.0, 1.0, 2.0]], CAMERA), "integer"),
    (lambda: rasterize_mesh(np.ones((3, 3)), [[0, 1, 2]], CAMERA, triangle_part=[300]), "triangle_part"),
    (lambda: render(np.zeros(5), MODEL, CAMERA), "shape"),
    (lambda: render(neutral_pose(), MODEL, CAMERA, edge_gap=-1.0), "gap"),
])
def test_bad_render_input_raises(call, match):
    with pytest.raises(ValueError, match=match):
        call()


@pytest.mark.parametrize("seed", range(4))
def test_the_fill_switch_sets_up_every_triangle_and_touches_no_pixel(seed):
    """``rasterize_triangles(..., fill=False)`` (the profile's stage switch) leaves the part and
    depth buffers untouched and grows the box over every triangle it set up: it holds the drawn
    box, which the filled render gives exactly (the bounds of its covered pixels)."""
    from mocap.body.kinematics import segment_transforms_into
    from mocap.render.rasterize import Buffers, Scene, project_vertices, rasterize_triangles

    q = random_pose(np.random.default_rng(100 + seed))
    scene, boxes = Scene.of(MODEL, CAMERA), {}
    for fill in (True, False):
        b = Buffers.of(MODEL, CAMERA)
        segment_transforms_into(q, scene.offsets, b.transforms)
        project_vertices(b.transforms, scene.vertices, scene.vertex_segment, scene.camera, b.vertex_x, b.vertex_y,
                         b.vertex_inverse_depth)
        rasterize_triangles(b.vertex_x, b.vertex_y, b.vertex_inverse_depth, scene.triangles, scene.triangle_part,
                            scene.width, scene.height, True, b.part_ids, b.inverse_depth, b.triangle_ids, b.coverage,
                            b.box, fill)
        boxes[fill] = b.box.copy()
        if fill:
            rows, cols = np.nonzero(b.part_ids.reshape(CAMERA.height, CAMERA.width))
            assert list(boxes[True]) == [cols.min(), rows.min(), cols.max(), rows.max()]
        else:
            assert not b.part_ids.any() and not b.inverse_depth.any()
    drawn, set_up = boxes[True], boxes[False]
    assert set_up[0] <= drawn[0] and set_up[1] <= drawn[1] and set_up[2] >= drawn[2] and set_up[3] >= drawn[3]
    assert set_up[0] >= 0 and set_up[1] >= 0 and set_up[2] < CAMERA.width and set_up[3] < CAMERA.height
