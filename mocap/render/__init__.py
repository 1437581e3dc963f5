"""Camera and CPU rasterizer: coloured silhouette, depth, part ids and occluding edges."""
from mocap.render.camera import DEFAULT_HFOV_DEG, DEFAULT_SIZE, NEAR_PLANE_M, Camera
from mocap.render.rasterize import (EDGE_DEPTH_GAP_M, Rendering, rasterize_mesh, render, render_labels,
                                    render_occluding_edges)

__all__ = ["Camera", "DEFAULT_HFOV_DEG", "DEFAULT_SIZE", "EDGE_DEPTH_GAP_M", "NEAR_PLANE_M", "Rendering",
           "rasterize_mesh", "render", "render_labels", "render_occluding_edges"]
