"""Evaluated Blender meshes as binary PLY files that kozu's `mesh` shape reads: one file per material slot.

Corners are welded by (vertex, shading normal, UV): smooth faces share vertices, flat faces and UV seams split them,
as Blender's own split normals do. Normals are Blender's corner normals (flat, smooth, auto-smooth and custom split
normals included), so kozu shades with the same normals Cycles does; tangents are MikkTSpace in both (kozu computes
them from these normals and UVs, Blender's normal-map node does the same).
"""
import numpy as np


def _corner_normals(mesh, n_loops):
    """Per-corner normals: Blender 4.1+ has mesh.corner_normals; 3.x computes split normals into the loops."""
    normals = np.empty(n_loops * 3, dtype=np.float32)
    if hasattr(mesh, "corner_normals"):
        mesh.corner_normals.foreach_get("vector", normals)
    else:
        mesh.calc_normals_split()
        mesh.loops.foreach_get("normal", normals)
    return normals.reshape(-1, 3)


def mesh_arrays(mesh):
    """The triangles of an evaluated mesh, welded per (vertex, normal, UV), grouped by material index.

    Returns {material_index: (positions (n, 3), normals (n, 3), uvs (n, 2) or None, triangles (t, 3))}."""
    mesh.calc_loop_triangles()
    tris = mesh.loop_triangles
    n_tri = len(tris)
    if n_tri == 0:
        return {}
    n_vert, n_loop = len(mesh.vertices), len(mesh.loops)
    co = np.empty(n_vert * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    tri_loops = np.empty(n_tri * 3, dtype=np.int64)
    tris.foreach_get("loops", tri_loops)
    tri_mat = np.empty(n_tri, dtype=np.int64)
    tris.foreach_get("material_index", tri_mat)
    loop_vert = np.empty(n_loop, dtype=np.int64)
    mesh.loops.foreach_get("vertex_index", loop_vert)
    normals = _corner_normals(mesh, n_loop)
    uv_layer = mesh.uv_layers.active
    uvs = None
    if uv_layer is not None and len(uv_layer.data) == n_loop:
        uvs = np.empty(n_loop * 2, dtype=np.float32)
        uv_layer.data.foreach_get("uv", uvs)
        uvs = uvs.reshape(-1, 2)

    out = {}
    for m in np.unique(tri_mat):
        corners = tri_loops.reshape(-1, 3)[tri_mat == m].reshape(-1)  # loop index of every corner
        # A key per corner: its vertex index, its normal and its UV, compared as raw bytes.
        cols = [loop_vert[corners].astype(np.int32).view(np.float32), normals[corners]]
        if uvs is not None:
            cols.append(uvs[corners])
        key = np.ascontiguousarray(np.hstack([c.reshape(len(corners), -1) for c in cols]))
        _, first, inverse = np.unique(key.view(np.dtype((np.void, key.dtype.itemsize * key.shape[1]))).ravel(),
                                      return_index=True, return_inverse=True)
        loops = corners[first]
        out[int(m)] = (co[loop_vert[loops]], normals[loops], uvs[loops] if uvs is not None else None,
                       inverse.reshape(-1, 3).astype(np.int32))
    return out


def write_ply(path, positions, normals, uvs, triangles):
    """A binary little-endian PLY: float x y z nx ny nz [u v], faces as uchar-counted int lists."""
    n, t = len(positions), len(triangles)
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("nx", "<f4"), ("ny", "<f4"), ("nz", "<f4")]
    if uvs is not None:
        fields += [("u", "<f4"), ("v", "<f4")]
    vert = np.empty(n, dtype=fields)
    for i, name in enumerate("xyz"):
        vert[name] = positions[:, i]
    for i, name in enumerate(("nx", "ny", "nz")):
        vert[name] = normals[:, i]
    if uvs is not None:
        vert["u"], vert["v"] = uvs[:, 0], uvs[:, 1]
    face = np.empty(t, dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"] = 3
    face["i"] = triangles
    header = ["ply", "format binary_little_endian 1.0", "comment written by kozu_blender", f"element vertex {n}"]
    header += [f"property float {name}" for name, _ in fields]
    header += [f"element face {t}", "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as f:
        f.write(("\n".join(header) + "\n").encode("ascii"))
        f.write(vert.tobytes())
        f.write(face.tobytes())
