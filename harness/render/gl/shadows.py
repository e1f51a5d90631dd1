"""Self-shadowing by an opacity shadow map: the hair and the bodies are drawn from the
light (orthographic, SIZE² texels) into a depth texture holding the first surface the
light meets. A fragment that lies Δ cm behind that surface receives exp(−σ·Δ) of the
light (the depth map filtered bilinearly): hair in front of other hair darkens it
the more hair it has passed through, the way opacity and deep shadow maps do, at the cost
of one depth pass. The numbers and the choice: docs/decisions/render.md."""

from dataclasses import dataclass


@dataclass(frozen=True)
class ShadowSettings:
    enabled: bool = True
    size: int = 1024  # texels a side
    sigma: float = 0.6  # 1/cm: the light left after Δ cm of hair is exp(−σ·Δ)
    bias_cm: float = 0.35  # depth past the first surface that still counts as lit
    width_texels: float = 1.0  # the hair ribbons' width in the light's map


class ShadowMap:
    """The light's depth texture and its framebuffer, made once per size."""

    def __init__(self, ctx, settings):
        self.settings = settings
        self.texture = ctx.depth_texture((settings.size, settings.size))
        self.texture.compare_func = ""  # read depths, not comparisons
        self.texture.repeat_x = self.texture.repeat_y = False
        self.framebuffer = ctx.framebuffer(depth_attachment=self.texture)

    def release(self):
        self.framebuffer.release()
        self.texture.release()
