"""The one OpenGL context: moderngl on EGL (no display), made once per process.

Where moderngl is not installed or EGL gives no context, `context()` raises
GLUnavailable (a HarnessError, exit 2) with one line saying why; `unavailable()` returns
that line or None, for steps that skip their renders."""

from harness import HarnessError

GL_VERSION = 330  # core profile with geometry shaders; llvmpipe gives 4.5

_context = None
_reason = None


class GLUnavailable(HarnessError):
    """No OpenGL context on EGL here (the reason is the message)."""


def context():
    """The process's moderngl context on EGL, made on first use."""
    global _context, _reason
    if _context is not None:
        return _context
    if _reason is not None:
        raise GLUnavailable(_reason)
    try:
        import moderngl
    except ImportError as e:
        _reason = f"render: moderngl is not installed ({e.name}): pip install -r requirements.lock"
        raise GLUnavailable(_reason) from None
    try:
        _context = moderngl.create_context(standalone=True, backend="egl", require=GL_VERSION)
    except Exception as e:  # glcontext raises plain Exceptions naming the EGL call that failed
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        _reason = f"render: no OpenGL {GL_VERSION // 100}.{GL_VERSION % 100 // 10} context on EGL ({first})"
        raise GLUnavailable(_reason) from None
    return _context


def unavailable():
    """None where a context can be made, else the one line saying why not."""
    try:
        context()
    except GLUnavailable as e:
        return str(e)
    return None


def describe():
    """The renderer's and driver's names, e.g. 'llvmpipe (LLVM 15.0.6, 256 bits), 4.5 (Core Profile) Mesa 22.3.6'."""
    info = context().info
    return f"{info['GL_RENDERER']}, {info['GL_VERSION']}"
