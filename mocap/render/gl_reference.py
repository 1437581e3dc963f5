"""The same body mesh rendered by OpenGL (Mesa llvmpipe through moderngl), for benchmarks.

Optional: needs the ``bench`` extra (``pip install -e .[bench]``) and Mesa's EGL driver
(``apt-get install -y libegl1 libegl-mesa0 libgl1-mesa-dri``). It does what the paper did on a
GPU — pose on the CPU, render the class-coloured silhouette with a depth test and back-face
culling, read the label image back — so the compiled rasterizer can be compared with it.
"""
from __future__ import annotations

import os

import numpy as np

from mocap.body.model import BodyModel
from mocap.body.skeleton import SEGMENT_NAMES
from mocap.render.camera import NEAR_PLANE_M, Camera

_VERTEX_SHADER = """
#version 330
uniform mat4 segments[%d];
uniform vec4 intrinsics;      // fx, fy, cx, cy (pixels)
uniform vec2 size;            // width, height (pixels)
uniform vec2 near_far;        // metres
in vec3 position;             // segment-local, metres
in int segment;
in float label;
flat out float v_label;
void main() {
    vec3 p = (segments[segment] * vec4(position, 1.0)).xyz;
    float n = near_far.x, f = near_far.y;
    float xc = (intrinsics.x * p.x + intrinsics.z * p.z) * 2.0 / size.x - p.z;
    float yc = -((intrinsics.y * p.y + intrinsics.w * p.z) * 2.0 / size.y - p.z);
    float zc = (p.z * (f + n) - 2.0 * f * n) / (f - n);
    gl_Position = vec4(xc, yc, zc, p.z);
    v_label = label;
}
""" % len(SEGMENT_NAMES)

_FRAGMENT_SHADER = """
#version 330
flat in float v_label;
out float label;
void main() { label = v_label / 255.0; }
"""


class GLRenderer:
    """Render class-label images of a body model with OpenGL on the CPU (llvmpipe).

    Parameters
    ----------
    model : BodyModel
    camera : Camera
    threads : int or None
        llvmpipe rendering threads (``LP_NUM_THREADS``); 1 compares one core with one core.

    Raises
    ------
    RuntimeError
        If moderngl or an EGL/OpenGL 3.3 context is not available (the message says how to get it).
    """

    def __init__(self, model: BodyModel, camera: Camera, *, threads: int | None = 1) -> None:
        try:
            import moderngl
        except ImportError:
            raise RuntimeError("moderngl is not installed: pip install -e .[bench]") from None
        if threads is not None:
            os.environ["LP_NUM_THREADS"] = str(int(threads))
        try:
            self.ctx = moderngl.create_standalone_context(backend="egl")
        except Exception as exc:  # moderngl raises plain Exception when no EGL driver loads
            raise RuntimeError(f"no EGL OpenGL context ({exc}); install Mesa: "
                               "apt-get install -y libegl1 libegl-mesa0 libgl1-mesa-dri") from None
        self.renderer_name = self.ctx.info["GL_RENDERER"]
        self.model, self.camera = model, camera
        prog = self.ctx.program(vertex_shader=_VERTEX_SHADER, fragment_shader=_FRAGMENT_SHADER)
        prog["intrinsics"].value = (camera.fx, camera.fy, camera.cx, camera.cy)
        prog["size"].value = (camera.width, camera.height)
        prog["near_far"].value = (NEAR_PLANE_M, 100.0)
        self.prog = prog
        mesh = model.mesh
        tri = mesh.triangles
        labels = model.part_label[mesh.triangle_part]
        # un-indexed so each triangle carries its own label (flat shading of the class colour)
        pos = mesh.vertices[tri.ravel()].astype("f4")
        seg = mesh.vertex_segment[tri.ravel()].astype("i4")
        lab = np.repeat(labels, 3).astype("f4")
        self.vbo = [self.ctx.buffer(pos.tobytes()), self.ctx.buffer(seg.tobytes()), self.ctx.buffer(lab.tobytes())]
        self.vao = self.ctx.vertex_array(prog, [(self.vbo[0], "3f", "position"), (self.vbo[1], "1i", "segment"),
                                                (self.vbo[2], "1f", "label")])
        self.fbo = self.ctx.simple_framebuffer((camera.width, camera.height), components=1, dtype="f1")
        self.ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        self.ctx.front_face = "cw"
        self._mat = np.zeros((len(SEGMENT_NAMES), 4, 4), "f4")
        self._mat[:, 3, 3] = 1.0

    def render_labels(self, pose) -> np.ndarray:
        """Class-label image, uint8 (height, width), row 0 at the top."""
        self._mat[:, :3, :] = self.model.segment_transforms(pose)
        self.prog["segments"].write(np.ascontiguousarray(self._mat.transpose(0, 2, 1)).tobytes())
        self.fbo.use()
        self.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        self.vao.render()
        raw = self.fbo.read(components=1, dtype="f1", alignment=1)
        return np.frombuffer(raw, np.uint8).reshape(self.camera.height, self.camera.width)[::-1]

    def release(self) -> None:
        """Free the OpenGL objects and context."""
        for obj in (self.vao, *self.vbo, self.fbo, self.prog):
            obj.release()
        self.ctx.release()
