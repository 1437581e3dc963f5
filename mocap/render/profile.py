"""The rasterizer's compiled stages, named for profiling (``experiments.evaluation_profile``).

Public aliases of :mod:`mocap.render._raster`'s kernels, so that a profile outside this package
can run them one at a time inside its own compiled loop, and :func:`setup_only_rasterizer`, an
instrumented copy of the rasterizer that sets every triangle up (culling, box, edge functions,
depth plane) and stops before its fill. Nothing in the library calls this module.
"""
from __future__ import annotations

import inspect
import textwrap

import numba

from mocap.render import _raster

#: The vertices transformed and projected: ``(transforms, vertices, vertex_segment, camera,
#: vertex_x, vertex_y, vertex_inverse_depth)`` (the order the rasterizer module passes them).
project_vertices = _raster._project_vertices
#: The triangles filled into the label and depth buffers (the rasterizer itself).
rasterize_triangles = _raster._rasterize
#: The drawn box of the label and depth buffers cleared.
clear_drawn = _raster._clear


def setup_only_rasterizer():
    """A compiled copy of :data:`rasterize_triangles` that stops each triangle before its fill
    (the box still grows as if it had drawn); same arguments. Compiled anew at each call."""
    src = textwrap.dedent(inspect.getsource(_raster._rasterize.py_func))
    marker = "        part_id = np.uint8(triangle_part[t] + 1)\n"
    if marker not in src:
        raise RuntimeError("the rasterizer's source changed: update setup_only_rasterizer's marker")
    src = src.replace(marker, marker + "        if n_rows > 0:\n"
                      "            bx0 = min(bx0, px0)\n            by0 = min(by0, py0)\n"
                      "            bx1 = max(bx1, px1)\n            by1 = max(by1, py1)\n            continue\n")
    src = src.replace("@jit\n", "").replace("def _rasterize(", "def _rasterize_setup(")
    namespace = dict(vars(_raster))
    exec(compile(src, "<setup-only rasterizer>", "exec"), namespace)
    return numba.njit(nogil=True)(namespace["_rasterize_setup"])


__all__ = ["clear_drawn", "project_vertices", "rasterize_triangles", "setup_only_rasterizer"]
