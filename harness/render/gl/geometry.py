"""Vertex data: strands as line segments with tangents, bodies as triangle meshes with
normals (object space). float32 and uint32, as the buffers take them."""

import numpy as np

STRAND_FORMAT = "3f 3f 1f 1f"  # position, tangent, t along the strand, the strand's tint
STRAND_ATTRIBUTES = ("in_pos", "in_tan", "in_t", "in_tint")


def strand_vertices(strands, seed=0):
    """(vertices [N·P][8] float32, indices [2·segments] uint32) of strands [N][P][3]: the
    tangent by central differences along each strand, t = k/(P−1), one tint a strand drawn
    from `seed`. A segment with a non-finite end is left out."""
    s = np.asarray(strands, dtype=np.float64)
    n, p = s.shape[:2]
    tangent = np.gradient(s, axis=1) if p > 2 else np.repeat(s[:, 1:] - s[:, :1], p, axis=1)
    norm = np.linalg.norm(tangent, axis=2, keepdims=True)
    tangent = np.divide(tangent, norm, out=np.zeros_like(tangent), where=norm > 0)
    t = np.broadcast_to(np.linspace(0.0, 1.0, p), (n, p))
    tint = np.broadcast_to(np.random.default_rng(seed).uniform(-1, 1, (n, 1)), (n, p))
    vertices = np.concatenate([s, tangent, t[..., None], tint[..., None]], axis=2).reshape(n * p, 8)
    first = (np.arange(n)[:, None] * p + np.arange(p - 1)).reshape(-1)
    finite = np.all(np.isfinite(vertices), axis=1)
    keep = finite[first] & finite[first + 1]
    vertices[~finite] = 0.0
    indices = np.stack([first[keep], first[keep] + 1], axis=1).reshape(-1)
    return vertices.astype(np.float32), indices.astype(np.uint32)


def sphere_mesh(radius, rings=48, sectors=96):
    """(vertices [n][3], normals [n][3], triangles [m][3]) of a UV sphere about the origin,
    its poles on ±y."""
    phi = np.linspace(0, np.pi, rings + 1)[:, None]  # from +y down
    theta = np.linspace(0, 2 * np.pi, sectors + 1)[None, :]
    normals = np.stack(
        np.broadcast_arrays(np.sin(phi) * np.sin(theta), np.cos(phi), np.sin(phi) * np.cos(theta)), axis=-1
    ).reshape(-1, 3)
    return radius * normals, normals, grid_triangles(rings, sectors)


def capsule_mesh(length, radius, rings=24, sectors=48):
    """A capsule along +y from the origin to (0, length, 0): two hemispheres of `radius`
    joined by a cylinder (vertices, normals, triangles)."""
    half = rings // 2
    phi = np.r_[np.linspace(0, np.pi / 2, half + 1), np.linspace(np.pi / 2, np.pi, half + 1)][:, None]
    lift = np.r_[np.full(half + 1, length), np.zeros(half + 1)][:, None]
    theta = np.linspace(0, 2 * np.pi, sectors + 1)[None, :]
    normals = np.stack(
        np.broadcast_arrays(np.sin(phi) * np.sin(theta), np.cos(phi), np.sin(phi) * np.cos(theta)), axis=-1
    )
    vertices = radius * normals + np.stack(np.broadcast_arrays(0 * lift, lift, 0 * lift), axis=-1)
    return vertices.reshape(-1, 3), normals.reshape(-1, 3), grid_triangles(2 * half + 1, sectors)


def grid_triangles(rows, columns):
    """Two triangles per cell of a (rows + 1) × (columns + 1) vertex grid."""
    r, c = np.meshgrid(np.arange(rows), np.arange(columns), indexing="ij")
    a = (r * (columns + 1) + c).reshape(-1)
    b, d = a + columns + 1, a + 1
    return np.concatenate([np.stack([a, b, d], 1), np.stack([d, b, b + 1], 1)])


def vertex_normals(vertices, triangles):
    """Area-weighted vertex normals of a triangle mesh."""
    v = np.asarray(vertices, float)
    tri = np.asarray(triangles, np.int64)
    face = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    normals = np.zeros_like(v)
    for k in range(3):
        np.add.at(normals, tri[:, k], face)
    norm = np.linalg.norm(normals, axis=1, keepdims=True)
    return np.divide(normals, norm, out=np.zeros_like(normals), where=norm > 0)


def interleaved(vertices, normals):
    """[n][6] float32: position then normal, as the body program reads them."""
    return np.concatenate([vertices, normals], axis=1).astype(np.float32)
