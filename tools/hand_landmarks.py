#!/usr/bin/env python3
"""Hand-picked ankle and thigh-top heights of the sample legs with a foot, measured without
knitfit: the reference that tests/integration/anatomy.rs holds knitfit's landmarks to.

    python tools/hand_landmarks.py samples/makehuman_body.glb [more.glb ...]

Needs numpy, scipy and trimesh. Only the skin is measured (the file's largest mesh by area;
eyes, teeth and tongue are separate meshes), welded. Horizontal sections (square to the file's
+Y) every 0.5 mm; a section's pieces are found by joining the crossed edges of the faces it cuts,
and a piece is closed when every point has two neighbours. Girth is the perimeter of a closed
piece's convex hull, as a tape measure reads it. The left leg is the one at +X.

- sole: the left leg's lowest vertex;
- ankle: the section of smallest girth of the left leg's closed piece 5 to 25 cm above the sole;
- thigh top: the crotch, the lowest section where a closed piece spans both sides of x = 0 (the
  legs' sections have joined); for a leg cut at the thigh, the highest section below the cut's
  rim (the open edges) that is closed all round.
"""
import sys

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull

STEP_M = 0.0005


def skin(path):
    scene = trimesh.load(path, force="scene")
    g = max(scene.geometry.values(), key=lambda m: m.area)
    m = trimesh.Trimesh(g.vertices, g.faces, process=True)
    m.merge_vertices()
    return m


def pieces(m, y):
    """The section at height y: (points, closed) per connected piece."""
    V, F = m.vertices, m.faces
    above = V[:, 1] >= y
    n_above = above[F].sum(axis=1)
    cut = F[(n_above == 1) | (n_above == 2)]
    if len(cut) == 0:
        return []
    ids, pts, joins = {}, [], []
    for f in cut:
        ends = []
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            if above[a] != above[b]:
                key = (min(a, b), max(a, b))
                if key not in ids:
                    p, q = V[key[0]], V[key[1]]
                    ids[key] = len(pts)
                    pts.append(p + (q - p) * (y - p[1]) / (q[1] - p[1]))
                ends.append(ids[key])
        joins.append(ends)
    pts, joins = np.array(pts), np.array(joins)
    n = len(pts)
    graph = coo_matrix((np.ones(len(joins)), (joins[:, 0], joins[:, 1])), shape=(n, n))
    count, label = connected_components(graph, directed=False)
    degree = np.bincount(joins.ravel(), minlength=n)
    return [(pts[label == c], bool(np.all(degree[label == c] == 2))) for c in range(count)]


def girth(pts):
    xz = pts[:, [0, 2]]
    hull = xz[ConvexHull(xz).vertices]
    return float(np.sum(np.linalg.norm(hull - np.roll(hull, 1, axis=0), axis=1)))


def measure(path):
    m = skin(path)
    V = m.vertices
    sole = V[V[:, 0] > 0, 1].min()
    top = V[:, 1].max()
    ankle = None
    for y in np.arange(sole + 0.05, sole + 0.25, STEP_M):
        left = [p for p, closed in pieces(m, y) if closed and p[:, 0].mean() > 0]
        if left:
            g = max(girth(p) for p in left)
            if ankle is None or g < ankle[1]:
                ankle = (y, g)
    thigh_top, kind = None, None
    for y in np.arange(sole + 0.3, min(top, sole + 1.2), STEP_M):
        if any(c and p[:, 0].min() < -0.01 and p[:, 0].max() > 0.01 for p, c in pieces(m, y)):
            thigh_top, kind = y, "crotch"
            break
    if thigh_top is None:
        edges, uses = np.unique(m.edges_sorted, axis=0, return_counts=True)
        rim_low = V[edges[uses == 1].ravel(), 1].min()
        for y in np.arange(rim_low, rim_low - 0.05, -STEP_M):
            left = [c for p, c in pieces(m, y) if p[:, 0].mean() > 0]
            if left and all(left):
                thigh_top, kind = y, "highest closed section below the cut"
                break
    print(
        f"{path}: sole y {sole:.4f}; ankle y {ankle[0]:.4f} (girth {ankle[1]:.4f} m); "
        f"thigh top y {thigh_top:.4f} ({kind})"
    )


if __name__ == "__main__":
    for path in sys.argv[1:]:
        measure(path)
