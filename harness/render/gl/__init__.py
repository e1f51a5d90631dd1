"""Hair drawn as shaded fibres with OpenGL on EGL (moderngl): no display needed, Mesa's
llvmpipe on a CPU-only machine, the NVIDIA driver on a GPU node (docs/decisions/render.md).

  context   the one EGL context, or one line saying why there is none
  shaders   the GLSL sources: camera-facing ribbons, Kajiya–Kay shading, bodies, shadow depth
  camera    the front, side and three-quarter views, fitted to what is drawn
  geometry  vertex buffers of strands and triangle meshes of bodies
  bodies    solid bodies (spheres, capsules, triangle meshes) and their per-frame transforms
  shading   the light and the shading parameters
  shadows   the opacity shadow map (hair darkening the hair and the head behind it)
  renderer  a frame: shadow pass, MSAA colour pass, resolve, read back
  output    PNG frames and GIF/MP4 animations, written atomically
  command   `python -m harness render FILE`
"""
