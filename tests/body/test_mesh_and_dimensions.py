import json
from collections import Counter

import numpy as np
import pytest
from hypothesis import given, strategies as st

from mocap.body import PART_NAMES, BodyDimensions, BodyModel, PartSize, build_mesh
from mocap.body.dimensions import SIZED_PART_NAMES
from mocap.body.skeleton import MESH_PART_NAMES
from mocap.body.mesh import part_mesh, part_resolution, signed_volume


def edge_directions(triangles):
    return Counter((int(a), int(b)) for t in triangles for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])))


@pytest.mark.parametrize("resolution", [4, 8, 12, 33])
@pytest.mark.parametrize("dims", [BodyDimensions(), BodyDimensions().without_extensions()], ids=["full", "paper"])
def test_every_part_is_closed_and_outward(resolution, dims):
    mesh = build_mesh(dims, resolution)
    sized = [p for p in SIZED_PART_NAMES if dims.has(p)]
    expected = 0
    for part in sized:
        n = part_resolution(part, resolution)
        expected += 2 * n * (n // 2 + 1)        # the hair cut moves rings, adds none
    assert mesh.n_triangles == expected
    assert part_resolution("torso", resolution) == resolution
    assert (mesh.triangle_part == MESH_PART_NAMES.index("hair")).any() == (dims.hairline is not None)
    for part in sized:
        # face and hair together are the closed head
        ids = [MESH_PART_NAMES.index(part)] + ([MESH_PART_NAMES.index("hair")] if part == "head" else [])
        tris = mesh.triangles[np.isin(mesh.triangle_part, ids)]
        directed = edge_directions(tris)
        # closed and consistently oriented: each directed edge once, its reverse once
        assert all(n == 1 for n in directed.values())
        assert all(directed[(b, a)] == 1 for a, b in directed)
        assert signed_volume(mesh.vertices, tris) > 0


def test_ellipsoid_volume_converges_to_analytic():
    v, t = part_mesh(0.3, 0.2, 0.1, e_long=1.0, e_cross=1.0, taper=0.0, resolution=96)
    analytic = 4.0 / 3.0 * np.pi * 0.15 * 0.1 * 0.05
    assert signed_volume(v, t) == pytest.approx(analytic, rel=5e-3)
    assert v[:, 1].min() == pytest.approx(0.0) and v[:, 1].max() == pytest.approx(0.3)


def test_resolution_and_classes_validated():
    for bad in (3, 129, 12.5, True, "12"):
        with pytest.raises(ValueError, match="resolution"):
            build_mesh(BodyDimensions(), bad)
    with pytest.raises(ValueError, match="unknown body part"):
        BodyModel.build(part_class={**{p: "skin" for p in PART_NAMES}, "tail": "skin"})
    with pytest.raises(ValueError, match="not one of"):
        BodyModel.build(part_class={p: "fur" for p in PART_NAMES})
    three = BodyModel.build(part_class={**{p: "clothes" for p in PART_NAMES}, "head": "skin", "r_hand": "glove",
                                        "l_hand": "glove", "neck": "skin"},
                            class_names=("skin", "clothes", "glove"))
    assert three.n_classes == 3 and three.part_label[PART_NAMES.index("r_hand")] == 3


def test_dimensions_json_round_trip(tmp_path):
    dims = BodyDimensions().replace("r_forearm", length=0.3).scaled(1.1)
    path = tmp_path / "dims.json"
    dims.to_json(path)
    assert json.loads(path.read_text())["units"] == "metres"
    back = BodyDimensions.from_json(path)
    assert back == dims
    assert back["r_forearm"].length == pytest.approx(0.33)


@pytest.mark.parametrize("make, match", [
    (lambda: PartSize(-0.1, 0.1, 0.1), "positive"),
    (lambda: PartSize(0.1, float("nan"), 0.1), "finite"),
    (lambda: PartSize(0.1, 0.1, 0.0), "positive"),
    (lambda: BodyDimensions().replace("tail", length=1.0), "unknown body part"),
    (lambda: BodyDimensions({"torso": PartSize(1, 1, 1)}), "missing"),
    (lambda: BodyDimensions().scaled(-2.0), "positive"),
    (lambda: BodyDimensions.from_dict({"parts": {"torso": {"length": 1}}}), "length, width and depth"),
    (lambda: BodyDimensions.from_dict({"units": "inches", "parts": {}}), "metres"),
])
def test_bad_dimensions_raise_clear_errors(make, match):
    with pytest.raises(ValueError, match=match):
        make()


@given(st.floats(allow_nan=True, allow_infinity=True), st.floats(allow_nan=True, allow_infinity=True),
       st.floats(allow_nan=True, allow_infinity=True))
def test_part_size_accepts_only_finite_positive(length, width, depth):
    ok = all(np.isfinite(v) and v > 0 for v in (length, width, depth))
    if ok:
        assert PartSize(length, width, depth).length == length
    else:
        with pytest.raises(ValueError):
            PartSize(length, width, depth)


def test_build_mesh_equals_the_part_by_part_tessellation():
    """The template build (unit parts scaled) gives the same numbers as tessellating every part
    afresh (tests/naive.py), on random sizes, hairlines, parts and resolutions."""
    from tests.naive import naive_build_mesh, naive_part_mesh
    rng = np.random.default_rng(3)
    base = BodyDimensions()
    for case in range(24):
        parts = {name: PartSize(*(np.array([s.length, s.width, s.depth]) * rng.uniform(0.6, 1.6, 3)))
                 for name, s in base.parts.items() if name != "lower_body" or case % 3}
        hairline = None if case % 4 == 0 else float(rng.uniform(-0.9, 0.95))
        dims = BodyDimensions(parts, hairline)
        resolution = int(rng.choice([4, 5, 8, 11, 12, 16, 24]))
        mesh = build_mesh(dims, resolution)
        vertices, vertex_segment, triangles, triangle_part = naive_build_mesh(dims, resolution)
        np.testing.assert_allclose(mesh.vertices, vertices, rtol=0, atol=1e-12)
        for got, want in ((mesh.vertex_segment, vertex_segment), (mesh.triangles, triangles),
                          (mesh.triangle_part, triangle_part)):
            assert got.dtype == want.dtype and np.array_equal(got, want)
        # a second build of the same topology (from the kept templates) with other sizes
        other = BodyDimensions({k: PartSize(s.length * 1.1, s.width, s.depth * 0.9) for k, s in parts.items()},
                               hairline)
        np.testing.assert_allclose(build_mesh(other, resolution).vertices, naive_build_mesh(other, resolution)[0],
                                   rtol=0, atol=1e-12)
    for cuts in ((), (0.7,), (0.725, 0.325), (0.2, 0.5, 0.8)):
        for sign in (1, -1):
            v, t = part_mesh(0.3, 0.2, 0.1, e_long=0.45, e_cross=0.7, taper=0.2, resolution=7, start=0.05,
                             axis_sign=sign, cuts=cuts)
            nv, nt = naive_part_mesh(0.3, 0.2, 0.1, e_long=0.45, e_cross=0.7, taper=0.2, resolution=7, start=0.05,
                                     axis_sign=sign, cuts=cuts)
            np.testing.assert_array_equal(v, nv)
            np.testing.assert_array_equal(t, nt)


def test_a_new_hairline_reuses_a_kept_topology_with_the_same_numbers():
    """A calibration's colour fit tries a new hairline at every evaluation: ``build_mesh`` then
    moves the head's rings of a kept topology (``_topology_for``). Every array is, bit for bit,
    what the hairline's own topology (``_topology``, built afresh) gives, with one hair cut and
    with two, with and without the lower body."""
    import dataclasses

    from mocap.body import mesh as body_mesh

    rng = np.random.default_rng(11)
    full = BodyDimensions()
    no_lower = BodyDimensions({k: v for k, v in full.parts.items() if k != "lower_body"})
    for dims in (full, no_lower):
        present = tuple(n for n in MESH_PART_NAMES if dims.has(n))
        for resolution in (4, 8, 12, 24):
            for hairline in (*rng.uniform(-0.95, 0.95, 12), -0.5, 0.45):
                moved = body_mesh._topology_for(resolution, float(hairline), present)
                body_mesh._topology.cache_clear()
                own = body_mesh._topology(resolution, float(hairline), present)
                assert own.head is not None and moved.head[:4] == own.head[:4]
                assert np.array_equal(moved.head[4], own.head[4])
                for field in dataclasses.fields(own):
                    if field.name != "head":
                        got, want = np.asarray(getattr(moved, field.name)), np.asarray(getattr(own, field.name))
                        assert got.dtype == want.dtype and np.array_equal(got, want), field.name


def test_build_mesh_keeps_no_topology_per_hairline():
    """``build_mesh`` takes a new hairline's topology from the kept one (``_topology_for``):
    hundreds of hairlines, as a calibration's colour fit tries, add no topology to the cache."""
    from mocap.body import mesh as body_mesh

    build_mesh(BodyDimensions().with_hairline(0.3), 8)
    kept = body_mesh._topology.cache_info().currsize
    for hairline in np.linspace(0.0, 0.9, 200):
        build_mesh(BodyDimensions().with_hairline(float(hairline)), 8)
    assert body_mesh._topology.cache_info().currsize == kept
