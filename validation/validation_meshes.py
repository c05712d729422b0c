"""Meshes for the validation (numpy only): readers for the fetched meshes (OBJ, ASCII PLY),
the generated thin box, and the clean-up lucent's loader does (`mesh::validate`,
`mesh::unfold`), written back as OBJ so that Mitsuba reads the triangles lucent renders.
"""

import numpy as np


def read_obj(path):
    """Vertices and triangles (polygons as fans) of an OBJ file."""
    v, t = [], []
    with open(path) as f:
        for line in f:
            w = line.split()
            if w[:1] == ["v"]:
                v.append([float(x) for x in w[1:4]])
            elif w[:1] == ["f"]:
                idx = [int(x.split("/")[0]) for x in w[1:]]
                idx = [i - 1 if i > 0 else len(v) + i for i in idx]
                t += [[idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1)]
    return np.array(v), np.array(t, dtype=np.int64)


def thin_box(size=(50.0, 50.0, 3.0), step=2.0):
    """A closed box in millimetres, centred on the origin, its large faces facing +-z, split
    into squares of about `step` mm (each side at least 2 across) so that lucent's faces are a
    few mean free paths wide. Outward counter-clockwise faces; vertices shared along edges."""
    n = [max(2, int(round(s / step))) for s in size]
    half = np.array(size) / 2
    verts, index, tris = [], {}, []

    def vid(p):
        key = tuple(np.round(p, 6))
        if key not in index:
            index[key] = len(verts)
            verts.append(p)
        return index[key]

    for axis in range(3):
        u, w = (axis + 1) % 3, (axis + 2) % 3
        for sign in (1.0, -1.0):
            for i in range(n[u]):
                for j in range(n[w]):
                    def corner(a, b):
                        p = np.zeros(3)
                        p[axis] = sign * half[axis]
                        p[u] = -half[u] + size[u] * a / n[u]
                        p[w] = -half[w] + size[w] * b / n[w]
                        return vid(p)
                    q = [corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)]
                    if sign < 0:
                        q = q[::-1]
                    tris += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    return np.array(verts), np.array(tris, dtype=np.int64)


def read_ascii_ply(path):
    """Vertices and triangles of an ASCII PLY (the dragon's: x y z first, then triangles)."""
    with open(path) as f:
        counts, props = {}, {}
        element = None
        for line in f:
            w = line.split()
            if w[:1] == ["element"]:
                element = w[1]
                counts[element], props[element] = int(w[2]), []
            elif w[:1] == ["property"]:
                props[element].append(w[-1])
            elif w[:1] == ["end_header"]:
                break
        xyz = [props["vertex"].index(k) for k in "xyz"]
        v = np.array([[float(x) for x in next(f).split()] for _ in range(counts["vertex"])])[:, xyz]
        t = [[int(x) for x in next(f).split()] for _ in range(counts["face"])]
    return v, np.array([r[1:4] for r in t if r[0] == 3], dtype=np.int64)


def clean_triangles(v, t):
    """What lucent's mesh::validate keeps: no degenerate faces, and of faces over the same three
    vertices the one whose winding the faces around it agree with (the first on a tie)."""
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    cross = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    longest = np.max([((b - a) ** 2).sum(1), ((c - b) ** 2).sum(1), ((a - c) ** 2).sum(1)], axis=0)
    ok = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2]) & (cross > 1e-12 * longest)
    groups = {}
    for f in np.nonzero(ok)[0]:
        groups.setdefault(tuple(sorted(t[f])), []).append(f)
    edges = lambda f: [(t[f][0], t[f][1]), (t[f][1], t[f][2]), (t[f][2], t[f][0])]
    directed = {}
    for g in groups.values():
        if len(g) == 1:
            for e in edges(g[0]):
                directed[e] = directed.get(e, 0) + 1
    agree = lambda f: sum(directed.get((j, i), 0) - directed.get((i, j), 0) for i, j in edges(f))
    keep = sorted(max(g, key=agree) for g in groups.values())  # max: the first of equal maxima
    return t[keep]


def unfold(v, t, max_passes=8):
    """What lucent's mesh::unfold does (in f64): the vertices of faces folded over their
    neighbours move to the mean of their neighbours, first each face's corner farthest from
    it, else all three, pass by pass while the count of folded faces falls. Returns the moved
    positions and the counts (found, left)."""
    v = v.copy()
    edge_faces = {}
    for f, tri in enumerate(t):
        for k in range(3):
            a, b = tri[k], tri[(k + 1) % 3]
            edge_faces.setdefault((min(a, b), max(a, b)), []).append(f)
    nbrs = [[] for _ in t]
    ring = {}
    for (a, b), fs in edge_faces.items():
        ring.setdefault(a, []).append(b)
        ring.setdefault(b, []).append(a)
        for f in fs:
            nbrs[f].extend(g for g in fs if g != f)

    def normals():
        c = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
        length = np.linalg.norm(c, axis=1, keepdims=True)
        return np.where(length > 0, c / np.where(length > 0, length, 1), 0)

    def folded():
        n = normals()
        out = []
        for f, tri in enumerate(t):
            if not n[f].any() or not nbrs[f]:
                continue
            total = n[nbrs[f]].sum(0)
            if not total.any() or n[f] @ total >= -0.5 * np.linalg.norm(total):
                continue
            if any(n[f] @ n[g] < 0 and any(n[f] @ (v[w] - v[tri[0]]) > 0 for w in t[g] if w not in tri) for g in nbrs[f]):
                out.append(f)
        return out

    def mean(w):
        return v[ring[w]].mean(0)

    now = folded()
    found = len(now)
    for _ in range(max_passes):
        if not now:
            break
        for every in (False, True):
            if every:
                verts = sorted({w for f in now for w in t[f]})
            else:
                verts = sorted({max(t[f], key=lambda w: ((v[w] - mean(w)) ** 2).sum()) for f in now})
            before, to = v[verts].copy(), np.array([mean(w) for w in verts])
            v[verts] = to
            after = folded()
            if len(after) < len(now):
                break
            v[verts] = before
        else:
            break
        now = after
    return v, found, len(now)


def write_obj(path, v, t):
    used = np.unique(t)
    index = np.full(len(v), -1)
    index[used] = np.arange(len(used))
    with open(path, "w") as f:
        f.write("# cleaned by validation/lucent_validation.py scenes\n")
        f.writelines(f"v {x:.7g} {y:.7g} {z:.7g}\n" for x, y, z in v[used])
        f.writelines(f"f {i + 1} {j + 1} {k + 1}\n" for i, j, k in index[t])
