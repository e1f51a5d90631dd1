"""Time the same frame drawn offscreen on EGL by the two libraries docs/decisions/render.md
compares: this project's renderer (moderngl, harness/render/gl) and VTK (vtkEGLRenderWindow:
polylines, line width in pixels, Phong lighting, MSAA, optionally its shadow-map pass).
Not a test: a measurement, printed as one line per case.

  python3 tools/render_compare.py STATE [--size 640x480] [--repeat 5]

STATE: any state file (its last frame and its head sphere are drawn)."""

import argparse
import os
import time

import numpy as np

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


def timed(draw, repeat):
    draw()  # the first frame compiles shaders and uploads
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(repeat):
        draw()
    return (time.perf_counter() - wall) / repeat * 1e3, (time.process_time() - cpu) / repeat * 1e3


def ours(strands, head, size, shadows, samples=4):
    from harness.render.gl import context
    from harness.render.gl.renderer import Renderer
    from harness.render.gl.shadows import ShadowSettings

    r = Renderer(*size, samples=samples, shadows=ShadowSettings(enabled=shadows))
    cam = r.camera("three-quarter", strands, [head])
    return (lambda: r.draw(strands, [head], cam)), context.describe()


def vtk_frame(strands, head, size, shadows):
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray

    n, p = strands.shape[:2]
    points = vtk.vtkPoints()
    points.SetData(numpy_to_vtk(strands.reshape(-1, 3).astype(np.float32), deep=True))
    lines = vtk.vtkCellArray()
    offsets = numpy_to_vtkIdTypeArray(np.arange(n + 1, dtype=np.int64) * p, deep=True)
    lines.SetData(offsets, numpy_to_vtkIdTypeArray(np.arange(n * p, dtype=np.int64), deep=True))
    poly = vtk.vtkPolyData()
    poly.SetPoints(points)
    poly.SetLines(lines)
    hair_map = vtk.vtkPolyDataMapper()
    hair_map.SetInputData(poly)
    hair = vtk.vtkActor()
    hair.SetMapper(hair_map)
    hair.GetProperty().SetColor(0.26, 0.15, 0.075)
    hair.GetProperty().SetLineWidth(1.25)
    sphere = vtk.vtkSphereSource()
    sphere.SetRadius(head.radius)
    sphere.SetThetaResolution(96)
    sphere.SetPhiResolution(48)
    head_map = vtk.vtkPolyDataMapper()
    head_map.SetInputConnection(sphere.GetOutputPort())
    head_actor = vtk.vtkActor()
    head_actor.SetMapper(head_map)
    head_actor.GetProperty().SetColor(0.8, 0.62, 0.5)
    ren = vtk.vtkRenderer()
    ren.AddActor(hair)
    ren.AddActor(head_actor)
    ren.SetBackground(0.93, 0.93, 0.92)
    if shadows:
        light = vtk.vtkLight()
        light.SetPosition(-30, 60, 40)
        light.SetFocalPoint(0, 0, 0)
        ren.AddLight(light)
        passes = vtk.vtkRenderPassCollection()
        baker = vtk.vtkShadowMapBakerPass()
        shadow = vtk.vtkShadowMapPass()
        shadow.SetShadowMapBakerPass(baker)
        passes.AddItem(baker)
        passes.AddItem(shadow)
        seq = vtk.vtkSequencePass()
        seq.SetPasses(passes)
        cam_pass = vtk.vtkCameraPass()
        cam_pass.SetDelegatePass(seq)
        ren.SetPass(cam_pass)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetMultiSamples(4)
    win.SetSize(*size)
    win.AddRenderer(ren)
    cam = ren.GetActiveCamera()
    cam.SetPosition(-0.72 * 90, 0.3 * 90, 0.72 * 90)
    cam.SetFocalPoint(0, -10, 0)
    cam.SetViewAngle(30)
    ren.ResetCameraClippingRange()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(win)

    def draw():
        poly.Modified()  # a new frame's points, as an animation uploads them
        win.Render()
        grab.Modified()
        grab.Update()
        return grab.GetOutput()

    draw()
    caps = [ln.split(":", 1)[1].strip() for ln in win.ReportCapabilities().splitlines() if "renderer string" in ln]
    return draw, f"VTK {vtk.vtkVersion.GetVTKVersion()} {win.GetClassName()}, {caps[0] if caps else '?'}"


def main():
    from harness.io.trajectory import open_trajectory
    from harness.render.gl import bodies

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("state")
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    with open_trajectory(args.state) as t:
        f = t.n_frames - 1
        strands = t.frame(f).reshape(t.n_strands, t.points, 3).astype(np.float64)
        head = bodies.head(t, f)
    print(f"{t.n_strands} strands x {t.points} points, {size[0]}x{size[1]}, 4x MSAA unless said, {args.repeat} frames")
    cases = [("moderngl, no MSAA", lambda *a: ours(*a, samples=0), False)]
    cases += [
        (name, make, shadows) for name, make in (("moderngl", ours), ("vtk", vtk_frame)) for shadows in (False, True)
    ]
    for name, make, shadows in cases:
        try:
            draw, where = make(strands, head, size, shadows)
            wall, cpu = timed(draw, args.repeat)
        except Exception as e:  # a library that cannot draw here says why, the other still runs
            print(f"{name} shadows={shadows}: failed: {str(e).strip().splitlines()[0] if str(e).strip() else e!r}")
            continue
        print(f"{name} shadows={shadows}: {wall:.1f} ms wall, {cpu:.1f} ms CPU a frame ({where})")


if __name__ == "__main__":
    main()
