"""A frame: the shadow pass into the light's depth map, the colour pass into a
multisampled framebuffer (MSAA: the ribbons' and bodies' edges anti-aliased), the resolve,
and the read-back as an [H][W][3] uint8 image (row 0 at the top).

`Renderer(width, height).draw(strands, bodies, camera)` draws any strands [N][P][3] and any
list of bodies (bodies.Sphere, Capsule, Mesh, each with its transform of the frame);
`render(strands, bodies, view, size)` fits a named view to them and draws once."""

import numpy as np

from harness.render.gl import camera as cameras
from harness.render.gl import geometry, shaders
from harness.render.gl.context import context
from harness.render.gl.shading import Shading, world_light
from harness.render.gl.shadows import ShadowMap, ShadowSettings

SAMPLES = 4  # MSAA samples (llvmpipe's most)


def _set(program, name, value):
    """A uniform, if the compiled program kept it (GL drops unused ones)."""
    if name not in program:
        return
    if isinstance(value, np.ndarray) and value.shape == (4, 4):
        program[name].write(value.T.astype("f4").tobytes())  # GL reads column-major
    else:
        program[name].value = value


def _set_all(program, values):
    for name, value in values.items():
        _set(program, name, value)


def _layout(program, fmt, names):
    """A buffer's format for `program`: the attributes it dropped skipped ('3f' → '3x4')."""
    kept, parts = [], []
    for part, name in zip(fmt.split(), names):
        if name in program:
            kept.append(name)
            parts.append(part)
        else:
            parts.append(f"{part[:-1]}x4")
    return (" ".join(parts), *kept)


def scene_points(strands, bodies):
    """The strand points and every body's placed mesh vertices, [n][3]."""
    points = [np.asarray(strands, float).reshape(-1, 3)]
    for b in bodies:
        v = b.mesh()[0]
        m = b.model()
        points.append(v @ m[:3, :3].T + m[:3, 3])
    return np.concatenate(points)


class Renderer:
    """Programs, framebuffers and the shadow map of one image size, made once."""

    def __init__(self, width, height, samples=SAMPLES, shading=None, shadows=None):
        self.ctx = ctx = context()
        self.size = (int(width), int(height))
        self.shading = shading or Shading()
        self.shadows = shadows or ShadowSettings()
        hair_vs, hair_gs = shaders.source(shaders.HAIR_VERTEX), shaders.source(shaders.HAIR_GEOMETRY)
        body_vs = shaders.source(shaders.BODY_VERTEX)
        depth_fs = shaders.source(shaders.DEPTH_FRAGMENT)
        self.hair = ctx.program(
            vertex_shader=hair_vs, geometry_shader=hair_gs, fragment_shader=shaders.source(shaders.HAIR_FRAGMENT)
        )
        self.hair_depth = ctx.program(vertex_shader=hair_vs, geometry_shader=hair_gs, fragment_shader=depth_fs)
        self.body = ctx.program(vertex_shader=body_vs, fragment_shader=shaders.source(shaders.BODY_FRAGMENT))
        self.body_depth = ctx.program(vertex_shader=body_vs, fragment_shader=depth_fs)
        self.samples = max(0, min(samples, ctx.max_samples))
        self.target = ctx.framebuffer(
            ctx.renderbuffer(self.size, samples=self.samples), ctx.depth_renderbuffer(self.size, samples=self.samples)
        )
        self.resolved = ctx.framebuffer(ctx.renderbuffer(self.size))
        self.shadow_map = ShadowMap(ctx, self.shadows) if self.shadows.enabled else None

    def release(self):
        for fb in (self.target, self.resolved):
            for a in (*fb.color_attachments, fb.depth_attachment):
                if a is not None:
                    a.release()
            fb.release()
        if self.shadow_map:
            self.shadow_map.release()
        for p in (self.hair, self.hair_depth, self.body, self.body_depth):
            p.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()

    def camera(self, view, strands, bodies):
        """The named view fitted to these strands and bodies."""
        return cameras.fitted(view, scene_points(strands, bodies), self.size[0] / self.size[1])

    def _hair_array(self, program, strands, seed):
        vertices, indices = geometry.strand_vertices(strands, seed)
        vbo, ibo = self.ctx.buffer(vertices.tobytes()), self.ctx.buffer(indices.tobytes())
        vao = self.ctx.vertex_array(
            program, [(vbo, *_layout(program, geometry.STRAND_FORMAT, geometry.STRAND_ATTRIBUTES))], ibo
        )
        return vao, (vao, vbo, ibo), len(indices)

    def _body_arrays(self, program, bodies):
        out = []
        for b in bodies:
            v, n, tri = b.mesh()
            vbo = self.ctx.buffer(geometry.interleaved(v, n).tobytes())
            ibo = self.ctx.buffer(np.asarray(tri, np.uint32).tobytes())
            vao = self.ctx.vertex_array(program, [(vbo, *_layout(program, "3f 3f", ("in_pos", "in_normal")))], ibo)
            out.append((b, vao, (vao, vbo, ibo)))
        return out

    def _draw_all(self, hair_prog, body_prog, strands, bodies, common, seed):
        import moderngl

        held = []
        try:
            if len(strands):
                vao, res, count = self._hair_array(hair_prog, strands, seed)
                held += res
                if count:
                    vao.render(moderngl.LINES)
            for b, vao, res in self._body_arrays(body_prog, bodies):
                held += res
                _set_all(body_prog, {"model": b.model(), "body_color": tuple(b.color), "face_marks": b.face_marks})
                vao.render(moderngl.TRIANGLES)
        finally:
            for r in held:
                r.release()

    def _shadow_pass(self, strands, bodies, light_cam):
        s = self.shadows
        fb = self.shadow_map.framebuffer
        fb.use()
        fb.clear(depth=1.0)
        self.ctx.viewport = (0, 0, s.size, s.size)
        _set_all(self.hair_depth, {"mvp": light_cam.mvp, "viewport": (s.size, s.size), "width_px": s.width_texels})
        _set_all(self.body_depth, {"mvp": light_cam.mvp})
        self._draw_all(self.hair_depth, self.body_depth, strands, bodies, {}, 0)

    def draw(self, strands, bodies, camera, light=None, seed=0):
        """The image [H][W][3] uint8 of strands [N][P][3] and bodies seen by `camera`;
        `light`: the world direction toward the light (default: up and left of the viewer)."""
        import moderngl

        ctx = self.ctx
        strands = (
            np.asarray(strands, float).reshape(-1, *np.shape(strands)[-2:]) if len(strands) else np.zeros((0, 2, 3))
        )
        l_dir = world_light(camera, light)
        sh, sd = self.shading, self.shadows
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)
        common = {"use_shadows": bool(self.shadow_map), "gamma": sh.gamma, "ambient": sh.ambient}
        if self.shadow_map:
            centre, radius = cameras.bounding_sphere(scene_points(strands, bodies))
            light_cam = cameras.light_camera(l_dir, centre, radius)
            self._shadow_pass(strands, bodies, light_cam)
            self.shadow_map.texture.use(location=0)
            common |= {
                "shadow_map": 0,
                "light_mvp": light_cam.mvp,
                "light_depth_cm": 2.0 * radius,
                "sigma": sd.sigma,
                "shadow_bias_cm": sd.bias_cm,
            }
        self.target.use()
        ctx.viewport = (0, 0, *self.size)
        self.target.clear(*sh.background, 1.0, depth=1.0)
        view = {"mvp": camera.mvp, "light_dir": tuple(l_dir), "eye": tuple(camera.eye)}
        _set_all(
            self.hair,
            common
            | view
            | {
                "viewport": self.size,
                "width_px": sh.width_px,
                **{k: getattr(sh, k) for k in ("root_color", "tip_color", "specular_color")},
                **{k: getattr(sh, k) for k in ("tint_amount", "kd", "ks", "shininess")},
            },
        )
        _set_all(self.body, common | view)
        self._draw_all(self.hair, self.body, strands, bodies, common, seed)
        ctx.copy_framebuffer(self.resolved, self.target)
        data = self.resolved.read(components=3, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(self.size[1], self.size[0], 3)[::-1].copy()


def render(strands, bodies, view="three-quarter", size=(640, 480), **options):
    """One image of strands and bodies from a named view fitted to them (options: Renderer's)."""
    with Renderer(*size, **options) as r:
        return r.draw(strands, bodies, r.camera(view, strands, bodies))
