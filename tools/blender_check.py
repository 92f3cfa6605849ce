"""Import knitfit's outputs into Blender (bpy as a Python module) and check what Blender made.

Setup (once; Python 3.11 is what the bpy 4.5 wheel needs; the venv is about 1 GB)::

    python3.11 -m venv tools/.venv-blender
    tools/.venv-blender/bin/pip install -r tools/blender_requirements.txt
    # = bpy==4.5.15 numpy==1.26.4 plyfile==1.1.3

Run (after e.g. ``knitfit fit --resolution 40x40 --out /tmp/bl_out``)::

    tools/.venv-blender/bin/python tools/blender_check.py OUT_DIR [--expect-attributes NAMES...]
                                                                  [--samples N]

``--expect-attributes`` names the per-vertex fields the leg must carry, in either spelling
(``_STITCH_DENSITY`` or ``stitch_density``); default: stitch_density stretch_course stretch_wale
coverage. The yarns (``yarns`` in the GLB, ``stocking.ply``) must carry course, wale and
yarn_kind, and tension too unless report.json's ``details.yarns.written`` is ``loops`` (a loop
polyline's points carry no tension, class or slack); the stocking surface must carry course, wale,
yarn_kind and tension. Where report.json is there, the yarn files' points and segments must be its
``details.yarns.points`` and ``segments``. Every other custom attribute found in the files is
compared as well, but its absence is not an error. Exit status: 0 all checks passed; 1 some
check failed (each is printed as ``FAIL <name>: why`` and listed at the end); 2 bad arguments,
a missing file or no bpy.

What it does, starting from an empty Blender file (``read_factory_settings(use_empty=True)``)
for each import:

* ``stocking.glb`` through ``bpy.ops.import_scene.gltf`` with its defaults (no option is needed
  for custom attributes). Blender makes the objects ``leg``, ``yarns`` and ``stocking`` (object
  and mesh named after the glTF node and mesh) in the scene collection. Custom glTF attributes
  (any name starting with ``_``) keep their name verbatim, underscore and upper case included:
  ``_STITCH_DENSITY`` etc. become POINT-domain FLOAT attributes. ``COLOR_0`` becomes the
  CORNER/BYTE_COLOR attribute ``Color`` (and a ``DefaultMaterial`` showing it), ``NORMAL`` the
  custom normals, ``TEXCOORD_0`` the UV map ``UVMap``; the yarns' two ``LINES`` primitives
  become loose edges (no faces) with the materials ``nylon`` and ``support``. The stocking's
  material ``stocking`` (``alphaMode`` ``BLEND``, double-sided) becomes a node material with
  ``surface_render_method`` ``BLENDED`` and no backface culling, a Color Attribute node's Color
  into the Principled BSDF's Base Color (through a Multiply by the file's base colour) and its
  Alpha straight into Alpha (``io_scene_gltf2/blender/imp/pbrMetallicRoughness.py``,
  ``base_color``; with ``OPAQUE`` the Alpha is left unlinked at 1). The script checks that wiring,
  and that the colour attribute is white with ``_COVERAGE`` (clamped to 0-1) as alpha, within the
  8-bit step of a BYTE_COLOR.
* ``leg.ply`` and ``stocking.ply`` through ``bpy.ops.wm.ply_import`` with
  ``forward_axis='NEGATIVE_Z', up_axis='Y'`` (the PLY is +Y up like glTF; the importer puts
  that rotation into the object's matrix, not the vertices; with the default axes the leg lies
  on its side). Objects are named after the file: ``leg``, ``stocking``. Every extra vertex
  property becomes a POINT FLOAT attribute under its PLY name (``stitch_density``, ``course``,
  even the uchar ``part``); ``red/green/blue`` become the POINT/FLOAT_COLOR attribute ``Col``;
  the ``edge`` element becomes loose edges (its ``yarn_kind``/``direction`` are dropped).

Vertex order. The glTF importer (Blender 4.5, ``io_scene_gltf2/blender/imp/mesh.py``) builds
each primitive's vertices from ``np.unique`` of its indices and appends the primitives: a
single primitive that uses every vertex keeps the file's order (leg, stocking), unused vertices
are dropped, and a vertex shared by several primitives is duplicated. knitfit's yarn node has
one ``LINES`` primitive per yarn kind sharing one accessor, so Blender's ``yarns`` has more
vertices than the file (a yarn point with both nylon and support segments appears twice). With
the default ``merge_vertices=False`` nothing is merged. The PLY importer (``merge_verts=False``)
keeps every vertex in file order. The script therefore does not rely on order: it predicts the
Blender vertex count from the file (sum over primitives of the distinct indices used) and maps
vertices by position. Positions are compared in Blender's frame: file (x, y, z) is
(x, -z, y) there (glTF: the importer converts the vertex data, compared in mesh space; PLY: the
object matrix above, compared in world space, its float32 cos(pi/2) = 7.5e-8 entries taken as
0); both conversions are then exact in float32.

Importer quirk (Blender 4.5 glTF importer, read in its source and reproduced): it keeps the
custom attributes in a Python ``set``, so their order in Blender's attribute list changes from
run to run, and a mesh mixing custom attributes of different widths (a SCALAR and a VEC3) fails
to import for some hash seeds (``np.concatenate`` shape error). knitfit writes only float
SCALAR custom attributes, which import correctly whatever the order.

"Same values (sampled)": the files are read independently (GLB: JSON and BIN chunks parsed here
with ``struct``/``numpy``; PLY: ``plyfile``). For each object a deterministic sample of file
vertices is taken (``--samples`` evenly spaced indices, plus each attribute's minimum and
maximum); for each sampled vertex every Blender vertex at its position (within 1e-6 m) must
exist and hold the file's value, up to float32 tolerance (1e-6 relative, at least 1e-6 absolute).
Where several file vertices share a position (a seam), the Blender value must match one of
them. Yarn edges are checked completely: the multiset of edges, as pairs of endpoint positions,
must be the file's.

Scale. A whole stocking at the real count (``outputs`` ``loops``: 3.4 million yarn points and
segments, ``stocking.glb`` 110 MB) checks in about 14 s and 1.7 GB on two slow cores (Blender's
own imports: under 1 s each; most of the rest sorts 6.7 million positions for the edges). The
sampled vertices are found through the positions sorted by x (a binary search, not a pass over
every vertex per sample). The edges are compared as sorted integer keys of their endpoints'
position ids, exactly equal positions first; only where that finds a difference does each
Blender vertex take the id of the nearest file position within 1e-6 m.
"""

from __future__ import annotations

import argparse
import json
import os
import struct
import sys
import tempfile

try:
    import numpy as np
    import plyfile
    import bpy
except ImportError as err:  # pragma: no cover - setup problem
    print(
        f"blender_check: {err}. Run it with the venv's Python (see the docstring):\n"
        "  python3.11 -m venv tools/.venv-blender && "
        "tools/.venv-blender/bin/pip install -r tools/blender_requirements.txt",
        file=sys.stderr,
    )
    sys.exit(2)

DEFAULT_LEG_ATTRIBUTES = ["stitch_density", "stretch_course", "stretch_wale", "coverage"]
# Every yarn point carries these; the grid's and `stitches` yarns also `tension` (and class,
# slack), `loops` yarns do not (report.json details.yarns.written says which were written).
YARN_ATTRIBUTES = ["course", "wale", "yarn_kind"]
YARN_ATTRIBUTES_UNLESS_LOOPS = ["tension"]
# The stocking surface carries tension whatever the yarns are.
SURFACE_ATTRIBUTES = ["course", "wale", "yarn_kind", "tension"]
GLB_NODES = ["leg", "yarns", "stocking"]
POS_TOL = 1e-6  # metres
REL_TOL = 1e-6  # float32 values go through unchanged; allow a few ulps

# File (+Y up) to Blender (+Z up): (x, y, z) -> (x, -z, y).
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def gltf_name(name: str) -> str:
    return "_" + name.strip("_").upper()


def ply_name(name: str) -> str:
    return name.strip("_").lower()


class Checks:
    """Collects PASS/FAIL lines."""

    def __init__(self) -> None:
        self.failed: list[str] = []
        self.count = 0

    def check(self, name: str, ok: bool, detail: str = "") -> bool:
        self.count += 1
        if not ok:
            self.failed.append(name)
            print(f"    FAIL {name}: {detail}")
        return ok


# ---------------------------------------------------------------- reading the files ourselves

COMPONENT_DTYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
TYPE_SIZES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


def read_glb(path: str) -> tuple[dict, bytes]:
    """The JSON document and the BIN chunk of a GLB file."""
    with open(path, "rb") as f:
        data = f.read()
    magic, version, length = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67 or version != 2 or length != len(data):
        raise ValueError(f"{path}: not a glTF 2.0 GLB (magic {magic:#x}, version {version})")
    offset, doc, bin_chunk = 12, None, b""
    while offset < length:
        chunk_len, chunk_type = struct.unpack_from("<II", data, offset)
        body = data[offset + 8 : offset + 8 + chunk_len]
        if chunk_type == 0x4E4F534A:  # JSON
            doc = json.loads(body)
        elif chunk_type == 0x004E4942:  # BIN
            bin_chunk = body
        offset += 8 + chunk_len
    if doc is None:
        raise ValueError(f"{path}: no JSON chunk")
    return doc, bin_chunk


def read_accessor(doc: dict, bin_chunk: bytes, index: int) -> np.ndarray:
    """An accessor as a (count, components) array ((count,) for SCALAR); BIN-chunk data only."""
    acc = doc["accessors"][index]
    if "sparse" in acc or "bufferView" not in acc:
        raise ValueError(f"accessor {index}: sparse or view-less accessors are not handled")
    view = doc["bufferViews"][acc["bufferView"]]
    if doc["buffers"][view["buffer"]].get("uri") is not None:
        raise ValueError(f"accessor {index}: external buffers are not handled")
    dtype = np.dtype(COMPONENT_DTYPES[acc["componentType"]])
    n, count = TYPE_SIZES[acc["type"]], acc["count"]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = view.get("byteStride") or dtype.itemsize * n
    if count == 0:
        return np.zeros((0, n) if n > 1 else 0, dtype)
    if start + stride * (count - 1) + dtype.itemsize * n > len(bin_chunk):
        raise ValueError(f"accessor {index}: runs past the end of the BIN chunk")
    # A strided view of the bytes: row i starts at start + i * stride.
    rows = np.lib.stride_tricks.as_strided(
        np.frombuffer(bin_chunk, np.uint8, offset=start), shape=(count, dtype.itemsize * n),
        strides=(stride, 1))
    out = np.ascontiguousarray(rows).view(dtype).reshape(count, n)
    return out[:, 0].copy() if n == 1 else out.copy()


class FileMesh:
    """One mesh as the file holds it, already in Blender's frame."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.positions = np.zeros((0, 3))  # Blender frame
        self.attributes: dict[str, np.ndarray] = {}
        self.edges = np.zeros((0, 2), dtype=np.int64)  # loose edges (file vertex indices)
        self.faces = 0
        self.expected_vertices = 0  # what Blender should create
        self.other_attributes: list[str] = []


def glb_meshes(path: str) -> tuple[dict[str, FileMesh], list[str]]:
    """The root nodes' meshes of a GLB, keyed by node name, and all root node names, over every
    scene: `knitfit fit` keeps the yarn lines in a second scene, which Blender imports as a
    collection left out of the view layer."""
    doc, bin_chunk = read_glb(path)
    roots = [doc["nodes"][i] for scene in doc["scenes"] for i in scene["nodes"]]
    out = {}
    for node in roots:
        if "mesh" not in node:
            continue
        mesh = doc["meshes"][node["mesh"]]
        fm = FileMesh(node.get("name", ""))
        prims = [p for p in mesh["primitives"] if "POSITION" in p["attributes"]]
        if len({p["attributes"]["POSITION"] for p in prims}) > 1:
            raise ValueError(f"{path}: mesh {mesh.get('name')!r}: primitives with different "
                             "POSITION accessors are not supported by this check")
        if not prims:
            out[fm.name] = fm
            continue
        attrs = prims[0]["attributes"]
        xyz = read_accessor(doc, bin_chunk, attrs["POSITION"]).astype(np.float64)
        fm.positions = xyz @ Y_UP_TO_Z_UP.T
        nverts = len(fm.positions)
        for key, acc in attrs.items():
            if key.startswith("_"):
                fm.attributes[key] = read_accessor(doc, bin_chunk, acc).astype(np.float64)
            elif key != "POSITION":
                fm.other_attributes.append(key)
        edges = []
        for p in prims:
            mode = p.get("mode", 4)
            idx = (read_accessor(doc, bin_chunk, p["indices"]).astype(np.int64)
                   if "indices" in p else np.arange(nverts))
            fm.expected_vertices += len(np.unique(idx))
            if mode == 1:
                edges.append(idx.reshape(-1, 2))
            elif mode == 4:
                fm.faces += len(idx) // 3
            else:
                raise ValueError(f"{path}: primitive mode {mode} is not handled by this check")
        if edges:
            fm.edges = np.concatenate(edges)
        out[fm.name] = fm
    return out, [n.get("name", "") for n in roots]


POSITION_PROPS = {"x", "y", "z"}
NON_ATTRIBUTE_PROPS = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha", "s", "t"}


def ply_mesh(path: str, name: str) -> FileMesh:
    ply = plyfile.PlyData.read(path)
    vertex = ply["vertex"].data
    fm = FileMesh(name)
    xyz = np.stack([vertex[c].astype(np.float64) for c in ("x", "y", "z")], axis=1)
    fm.positions = xyz @ Y_UP_TO_Z_UP.T  # the import below uses up_axis='Y'
    fm.expected_vertices = len(xyz)
    for prop in vertex.dtype.names:
        if prop not in NON_ATTRIBUTE_PROPS:
            fm.attributes[prop] = vertex[prop].astype(np.float64)
        elif prop not in POSITION_PROPS:
            fm.other_attributes.append(prop)
    names = [e.name for e in ply.elements]
    if "edge" in names:
        edge = ply["edge"].data
        fm.edges = np.stack([edge["vertex1"], edge["vertex2"]], axis=1).astype(np.int64)
    if "face" in names:
        fm.faces = len(ply["face"].data)
    return fm


# ---------------------------------------------------------------------- what Blender holds


def fresh_blender() -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)


def find_object(name: str):
    obj = bpy.data.objects.get(name)
    if obj is None:  # e.g. "leg.001" if the name was taken
        cands = [o for o in bpy.data.objects if o.name.split(".")[0] == name]
        obj = cands[0] if cands else None
    return obj


def blender_positions(obj, world: bool) -> np.ndarray:
    mesh = obj.data
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3).astype(np.float64)
    if world:
        m = np.array(obj.matrix_world, dtype=np.float64)
        # The PLY importer's axis conversion is a quarter turn held in float32: its zeros are
        # cos(pi/2) = 7.5e-8, which would move the vertices by up to 6e-8 m. Entries that close
        # to -1, 0 or 1 are taken as exactly that, so the positions stay the file's.
        snapped = np.round(m)
        near = np.abs(m - snapped) <= 1e-6
        m[near] = snapped[near]
        co = co @ m[:3, :3].T + m[:3, 3]
    return co


def blender_values(attr) -> np.ndarray:
    vals = np.empty(len(attr.data), dtype=np.float32)
    attr.data.foreach_get("value", vals)
    return vals.astype(np.float64)


def position_ids(*position_sets: np.ndarray) -> list[np.ndarray]:
    """One integer per distinct position (exactly equal coordinates), shared across the sets."""
    allpos = np.concatenate(position_sets)
    order = np.lexsort(allpos.T[::-1])
    srt = allpos[order]
    new = np.ones(len(srt), dtype=bool)
    new[1:] = (srt[1:] != srt[:-1]).any(axis=1)
    ids = np.empty(len(allpos), dtype=np.int64)
    ids[order] = np.cumsum(new) - 1
    out, start = [], 0
    for p in position_sets:
        out.append(ids[start:start + len(p)])
        start += len(p)
    return out


def ids_within_tolerance(bpos: np.ndarray, fpos: np.ndarray, fid: np.ndarray) -> np.ndarray:
    """For each Blender position, the id (``fid``) of the nearest file position (largest
    coordinate difference) within POS_TOL, or a negative id of its own where there is none.
    Vectorised: the file positions sorted by x, each Blender position's window of candidates
    walked one step at a time."""
    order = np.argsort(fpos[:, 0], kind="stable")
    xs = fpos[order, 0]
    lo = np.searchsorted(xs, bpos[:, 0] - POS_TOL, side="left")
    hi = np.searchsorted(xs, bpos[:, 0] + POS_TOL, side="right")
    out = -1 - np.arange(len(bpos), dtype=np.int64)
    best = np.full(len(bpos), np.inf)
    todo = np.flatnonzero(lo < hi)
    step = 0
    while len(todo):
        cand = order[lo[todo] + step]
        dist = np.abs(fpos[cand] - bpos[todo]).max(axis=1)
        better = (dist <= POS_TOL) & (dist < best[todo])
        out[todo[better]] = fid[cand[better]]
        best[todo[better]] = dist[better]
        step += 1
        todo = todo[lo[todo] + step < hi[todo]]
    return out


def edges_differing(bpos: np.ndarray, bedges: np.ndarray, fpos: np.ndarray,
                    fedges: np.ndarray) -> int:
    """How many edges, as unordered pairs of endpoint positions, Blender and the file do not
    have in common (multisets; an edge missing on either side counts). Each position gets an
    integer id, each edge the int64 key of its two ids, and the sorted keys are compared, so
    millions of edges take seconds. Ids are first given to exactly equal positions (the
    conversions are exact, so this is the usual verdict); only when that finds a difference is
    each Blender vertex given the id of a file position within POS_TOL."""
    bid, fid = position_ids(bpos, fpos)
    n = int(max(bid.max(initial=-1), fid.max(initial=-1))) + 1

    def keys(ids, edges):
        a, b = ids[edges[:, 0]], ids[edges[:, 1]]
        lo_, hi_ = np.minimum(a, b), np.maximum(a, b)
        # An edge with an end at no file position (negative id) matches no file edge: -1.
        return np.where(lo_ >= 0, lo_ * n + hi_, -1)

    kb, kf = keys(bid, bedges), keys(fid, fedges)
    if len(kb) == len(kf) and np.array_equal(np.sort(kb), np.sort(kf)):
        return 0
    fid_only = position_ids(fpos)[0]
    n = int(fid_only.max(initial=-1)) + 1
    kb = keys(ids_within_tolerance(bpos, fpos, fid_only), bedges)
    kf = keys(fid_only, fedges)
    ub, cb = np.unique(kb, return_counts=True)
    uf, cf = np.unique(kf, return_counts=True)
    _, ib, jf = np.intersect1d(ub, uf, assume_unique=True, return_indices=True)
    common = int(np.minimum(cb[ib], cf[jf]).sum())
    return max(len(kb), len(kf)) - common


class PositionIndex:
    """The points within POS_TOL (every coordinate) of a position: the points sorted by x, a
    binary search on x, then the candidates' other coordinates checked. The same answer as
    comparing against every point, without a pass over millions of points per lookup."""

    def __init__(self, positions: np.ndarray) -> None:
        self.positions = positions
        self.order = np.argsort(positions[:, 0], kind="stable")
        self.xs = positions[self.order, 0]

    def near(self, p: np.ndarray) -> np.ndarray:
        lo = np.searchsorted(self.xs, p[0] - POS_TOL, side="left")
        hi = np.searchsorted(self.xs, p[0] + POS_TOL, side="right")
        cand = self.order[lo:hi]
        return np.sort(cand[np.abs(self.positions[cand] - p).max(axis=1) <= POS_TOL])


def describe_attributes(mesh) -> list[str]:
    return [f"{a.name} {a.domain}/{a.data_type}" for a in mesh.attributes
            if not a.is_internal and not a.name.startswith(".")]


def check_object(checks: Checks, label: str, obj_name: str, fm: FileMesh, required: list[str],
                 world: bool, loose_edges: bool, samples: int) -> None:
    """Counts, attributes and sampled values of one imported object against the file."""
    obj = find_object(obj_name)
    if not checks.check(f"{label}.object", obj is not None and obj.type == "MESH",
                        f"no mesh object named {obj_name!r} (objects: "
                        f"{[o.name for o in bpy.data.objects]})"):
        return
    mesh = obj.data
    nv, ne, nf = len(mesh.vertices), len(mesh.edges), len(mesh.polygons)
    is_loose = np.zeros(ne, dtype=bool)
    mesh.edges.foreach_get("is_loose", is_loose)
    loose = int(is_loose.sum())
    print(f"  object {obj.name!r} (mesh {mesh.name!r}): {nv} vertices, {ne} edges "
          f"({loose} loose), {nf} faces; file: {len(fm.positions)} vertices, "
          f"{len(fm.edges)} edges, {fm.faces} faces")
    mats = [m.name if m else None for m in mesh.materials]
    if mats:
        print(f"    materials: {', '.join(map(str, mats))}")
    print(f"    attributes: {'; '.join(describe_attributes(mesh))}")
    checks.check(f"{label}.vertex_count", nv == fm.expected_vertices,
                 f"Blender has {nv} vertices, expected {fm.expected_vertices}")
    checks.check(f"{label}.face_count", nf == fm.faces, f"Blender has {nf} faces, file {fm.faces}")
    if loose_edges:
        checks.check(f"{label}.edges", ne == len(fm.edges) and loose == ne and nf == 0,
                     f"{ne} edges, {loose} loose, {nf} faces; file has {len(fm.edges)} edges")
    else:
        checks.check(f"{label}.no_loose_edges", loose == 0, f"{loose} loose edges")

    bpos = blender_positions(obj, world)
    same_order = len(bpos) == len(fm.positions) and (
        len(bpos) == 0 or np.abs(bpos - fm.positions).max() <= POS_TOL)
    if same_order:
        print("    vertex order: as in the file")
    else:
        print(f"    vertex order: differs from the file ({nv - len(fm.positions):+d} vertices; "
              "values matched by position)")

    if loose_edges and len(fm.edges):
        bedges = np.empty(ne * 2, dtype=np.int64)
        mesh.edges.foreach_get("vertices", bedges)
        bad = edges_differing(bpos, bedges.reshape(-1, 2), fm.positions, fm.edges)
        ok = bad == 0
        print(f"    edges: {ne} loose edges, endpoint positions "
              f"{'the same as' if ok else 'DIFFERENT from'} the file's {len(fm.edges)} edges "
              "(all compared)")
        checks.check(f"{label}.edge_endpoints", ok,
                     f"{bad} of {len(fm.edges)} edges (as pairs of endpoint positions) differ "
                     "from the file's")

    # Deterministic sample of file vertices: evenly spaced, plus each attribute's extremes.
    n = len(fm.positions)
    picks = set(np.linspace(0, n - 1, num=min(samples, n)).round().astype(int).tolist()) if n else set()
    for vals in fm.attributes.values():
        if n:
            picks.update((int(np.argmin(vals)), int(np.argmax(vals))))
    picks = sorted(picks)
    # For each sampled file vertex: the Blender vertices at its position, and the file vertices
    # sharing that position (to allow seams).
    matches = []
    missing = []
    shared = 0
    bindex, findex = PositionIndex(bpos), PositionIndex(fm.positions)
    for i in picks:
        b = bindex.near(fm.positions[i])
        f = findex.near(fm.positions[i])
        if len(b) == 0:
            missing.append(i)
        shared += len(f) > 1
        matches.append((i, b, f))
    checks.check(f"{label}.sampled_vertices_present", not missing,
                 f"{len(missing)} of {len(picks)} sampled file vertices have no Blender vertex "
                 f"at their position (e.g. file vertex {missing[:3]})")
    if shared:
        print(f"    {shared} of {len(picks)} sampled vertices share their position with another file vertex")

    names = list(dict.fromkeys(required + sorted(fm.attributes)))
    width = max([len(x) for x in names] + [16])
    for name in names:
        in_file = name in fm.attributes
        attr = mesh.attributes.get(name)
        what = []
        if not in_file:
            what.append("not in the file")
        if attr is None:
            what.append("not in Blender")
        elif (attr.domain, attr.data_type) != ("POINT", "FLOAT"):
            what.append(f"is {attr.domain}/{attr.data_type}, not POINT/FLOAT")
        req = " (required)" if name in required else ""
        if what:
            print(f"    {name:<{width}} {'; '.join(what)}{req}")
            checks.check(f"{label}.attribute.{name}", False, "; ".join(what))
            continue
        bvals = blender_values(attr)
        fvals = fm.attributes[name]
        worst, worst_rel, compared = 0.0, 0.0, 0
        for i, b, f in matches:
            for bi in b:
                d = np.abs(fvals[f] - bvals[bi]).min()
                lim = max(POS_TOL, REL_TOL * abs(fvals[i]))
                worst = max(worst, d)
                worst_rel = max(worst_rel, d / lim)
                compared += 1
        ok = worst_rel <= 1.0
        print(f"    {name:<{width}} {attr.domain}/{attr.data_type}  range [{fvals.min():.6g}, "
              f"{fvals.max():.6g}]  {compared} sampled  max |diff| {worst:.3g}"
              f"{'' if ok else '  <-- MISMATCH'}{req}")
        checks.check(f"{label}.values.{name}", ok,
                     f"max |Blender - file| = {worst:.3g} over {compared} sampled vertices")
    if fm.other_attributes:
        print(f"    not compared: {', '.join(fm.other_attributes)}")


def upstream(socket, seen=None) -> list:
    """Every node that feeds `socket`, through any chain of links (nearest first)."""
    seen = [] if seen is None else seen
    for link in socket.links:
        node = link.from_node
        if node not in seen:
            seen.append(node)
            for inp in node.inputs:
                upstream(inp, seen)
    return seen


def feeds(socket, node_type: str, output: str) -> bool:
    """Whether output `output` of a node of type `node_type` reaches `socket` through links."""
    def reaches(sock) -> bool:
        for link in sock.links:
            if link.from_node.bl_idname == node_type and link.from_socket.name == output:
                return True
            if any(reaches(i) for i in link.from_node.inputs):
                return True
        return False
    return reaches(socket)


def check_stocking_material(checks: Checks, path: str) -> None:
    """The stocking surface's material as Blender imported it: blended, double-sided, the file's
    base colour, and the colour attribute's alpha (the file's COLOR_0 alpha, the coverage) wired
    into the Principled BSDF's Alpha; the alpha values against ``_COVERAGE`` clamped to 0-1."""
    doc, _ = read_glb(path)
    node = next((n for n in doc["nodes"] if n.get("name") == "stocking" and "mesh" in n), None)
    prim = doc["meshes"][node["mesh"]]["primitives"][0] if node else {}
    if not checks.check("glb.stocking.file_material", "material" in prim,
                        "the file's stocking primitive has no material"):
        return
    gmat = doc["materials"][prim["material"]]
    factor = gmat.get("pbrMetallicRoughness", {}).get("baseColorFactor", [1, 1, 1, 1])
    obj = find_object("stocking")
    mats = [m for m in (obj.data.materials if obj else []) if m]
    print(f"  stocking material (file {gmat.get('name')!r}, alphaMode "
          f"{gmat.get('alphaMode', 'OPAQUE')}, doubleSided {gmat.get('doubleSided', False)}, "
          f"baseColorFactor {factor}): Blender {[m.name for m in mats]}")
    if not checks.check("glb.stocking.material", len(mats) == 1 and mats[0].use_nodes,
                        f"materials {[m.name for m in mats]}, wanted one node material"):
        return
    mat = mats[0]
    print(f"    surface_render_method {mat.surface_render_method!r}, use_backface_culling "
          f"{mat.use_backface_culling}")
    checks.check("glb.stocking.material_blended", mat.surface_render_method == "BLENDED",
                 f"surface_render_method {mat.surface_render_method!r}")
    checks.check("glb.stocking.material_double_sided",
                 mat.use_backface_culling == (gmat.get("doubleSided") is not True),
                 f"use_backface_culling {mat.use_backface_culling}")
    bsdf = next((n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled"),
                None)
    if not checks.check("glb.stocking.principled", bsdf is not None, "no Principled BSDF"):
        return
    alpha_in, colour_in = bsdf.inputs["Alpha"], bsdf.inputs["Base Color"]
    chain = [n.bl_idname for n in upstream(alpha_in)]
    print(f"    Principled Alpha <- {' <- '.join(chain) or 'unlinked, ' + str(alpha_in.default_value)}")
    checks.check("glb.stocking.alpha_from_colour_attribute",
                 feeds(alpha_in, "ShaderNodeVertexColor", "Alpha"),
                 f"the Alpha input is not fed by a Color Attribute's Alpha ({chain})")
    checks.check("glb.stocking.colour_from_colour_attribute",
                 feeds(colour_in, "ShaderNodeVertexColor", "Color"),
                 "the Base Color input is not fed by a Color Attribute's Color")
    # The factor's colour sits on a Multiply mix, or on the socket when it is white.
    defaults = [list(i.default_value)[:3] for n in upstream(colour_in) if n.bl_idname == "ShaderNodeMix"
                for i in n.inputs if i.type == "RGBA" and not i.is_linked]
    defaults.append(list(colour_in.default_value)[:3])
    checks.check("glb.stocking.base_colour",
                 any(np.allclose(d, factor[:3], atol=1e-6) for d in defaults),
                 f"no unlinked colour {factor[:3]} on the base colour chain ({defaults})")
    checks.check("glb.stocking.alpha_factor", factor[3] == 1 or feeds(alpha_in, "ShaderNodeMath",
                                                                       "Value"),
                 f"baseColorFactor alpha {factor[3]} is not applied")

    mesh = obj.data
    colour = mesh.color_attributes.get("Color")
    coverage = mesh.attributes.get("_COVERAGE")
    if not checks.check("glb.stocking.colour_attribute", colour is not None and coverage is not None,
                        f"colour attributes {[a.name for a in mesh.color_attributes]}, "
                        f"_COVERAGE {'present' if coverage is not None else 'absent'}"):
        return
    rgba = np.empty(len(colour.data) * 4, dtype=np.float32)
    colour.data.foreach_get("color", rgba)
    rgba = rgba.reshape(-1, 4)
    cov = np.clip(blender_values(coverage), 0.0, 1.0)
    if colour.domain == "CORNER":
        loops = np.empty(len(mesh.loops), dtype=np.int64)
        mesh.loops.foreach_get("vertex_index", loops)
        cov = cov[loops]
    # A BYTE_COLOR alpha is stored in 8 bits (rounded: half a step at most; a step allowed).
    worst = float(np.abs(rgba[:, 3] - cov).max()) if len(cov) else 0.0
    white = float(np.abs(rgba[:, :3] - 1.0).max()) if len(cov) else 0.0
    print(f"    colour attribute {colour.name!r} {colour.domain}/{colour.data_type}: alpha vs "
          f"clamped _COVERAGE max |diff| {worst:.3g} over {len(cov)}, RGB max |1 - c| {white:.3g}")
    checks.check("glb.stocking.alpha_is_coverage", worst <= 1 / 255 + 1e-6,
                 f"max |alpha - clamp(_COVERAGE)| = {worst:.3g}")
    checks.check("glb.stocking.colour_is_white", white <= 1e-6, f"max |1 - RGB| = {white:.3g}")


def run_import(checks: Checks, label: str, fn) -> bool:
    """Runs an import operator, its console output (C++ and Python loggers write to the file
    descriptors directly) captured and printed indented."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile(mode="w+b") as log:
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        try:
            result, error = fn(), None
        except Exception as err:  # noqa: BLE001 - an importer failure is a failed check
            result, error = None, err
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
        log.seek(0)
        for line in log.read().decode("utf-8", "replace").splitlines():
            if line.strip():
                print(f"  importer: {line.strip()}")
    if error is not None:
        return checks.check(f"{label}.import", False, f"{type(error).__name__}: {error}")
    return checks.check(f"{label}.import", result == {"FINISHED"}, f"operator returned {result}")


def read_report_yarns(out_dir: str) -> dict | None:
    """``details.yarns`` of the fit's report.json (what the yarn files hold), or None."""
    try:
        with open(os.path.join(out_dir, "report.json"), encoding="utf-8") as f:
            yarns = json.load(f)["details"]["yarns"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return yarns if isinstance(yarns, dict) else None


def check_report_counts(checks: Checks, label: str, fm: FileMesh, report: dict | None) -> None:
    """The yarn file's points and segments against report.json's ``details.yarns``."""
    if report is None or "points" not in report or "segments" not in report:
        return
    ok = len(fm.positions) == report["points"] and len(fm.edges) == report["segments"]
    print(f"  {label} yarns: {len(fm.positions)} points, {len(fm.edges)} segments in the file; "
          f"report.json: {report['points']} points, {report['segments']} segments")
    checks.check(f"{label}.report_counts", ok,
                 f"file {len(fm.positions)} points / {len(fm.edges)} segments, report.json "
                 f"{report['points']} / {report['segments']}")


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(
        description="Import knitfit's stocking.glb, leg.ply and stocking.ply into Blender (bpy) "
                    "and check objects, attributes and sampled values.")
    parser.add_argument("out_dir", metavar="OUT_DIR")
    parser.add_argument("--expect-attributes", nargs="*", metavar="NAME",
                        default=DEFAULT_LEG_ATTRIBUTES,
                        help="leg attributes that must be present (glTF or PLY spelling; default: "
                             + " ".join(DEFAULT_LEG_ATTRIBUTES) + ")")
    parser.add_argument("--samples", type=int, default=50,
                        help="evenly spaced vertices sampled per object (default 50)")
    args = parser.parse_args(argv)

    paths = {f: os.path.join(args.out_dir, f) for f in ("stocking.glb", "leg.ply", "stocking.ply")}
    absent = [p for p in paths.values() if not os.path.isfile(p)]
    if absent:
        print(f"blender_check: missing {', '.join(absent)}", file=sys.stderr)
        return 2
    leg_glb = [gltf_name(a) for a in args.expect_attributes]
    leg_ply = [ply_name(a) for a in args.expect_attributes]
    report = read_report_yarns(args.out_dir)
    written = (report or {}).get("written")
    yarn_required = YARN_ATTRIBUTES + (YARN_ATTRIBUTES_UNLESS_LOOPS if written != "loops" else [])
    yarn_glb = [gltf_name(a) for a in yarn_required]
    surface_glb = [gltf_name(a) for a in SURFACE_ATTRIBUTES]

    print(f"knitfit Blender check of {os.path.abspath(args.out_dir)} "
          f"(Blender {bpy.app.version_string}, bpy module)")
    print(f"required leg attributes: {' '.join(leg_glb) or '(none)'}")
    if report is None:
        print("yarns written: unknown (no report.json details.yarns); assumed to carry "
              f"{' '.join(yarn_glb)}")
    else:
        print(f"yarns written: {written!r} (report.json: {report.get('points')} points, "
              f"{report.get('segments')} segments); required yarn attributes: "
              f"{' '.join(yarn_glb)}")
    checks = Checks()

    # --- stocking.glb
    path = paths["stocking.glb"]
    print(f"\n{path}: bpy.ops.import_scene.gltf (defaults: merge_vertices=False, "
          "import_shading='NORMALS')")
    try:
        meshes, roots = glb_meshes(path)
    except (ValueError, KeyError, json.JSONDecodeError) as err:
        checks.check("glb.read", False, str(err))
        meshes, roots = {}, []
    if meshes or roots:
        checks.check("glb.file_nodes", all(n in meshes for n in GLB_NODES),
                     f"file root nodes with meshes: {sorted(meshes)}; wanted {GLB_NODES}")
        if "yarns" in meshes:
            check_report_counts(checks, "glb.yarns", meshes["yarns"], report)
        fresh_blender()
        if run_import(checks, "glb", lambda: bpy.ops.import_scene.gltf(filepath=path)):
            print(f"  Blender objects: {', '.join(sorted(o.name for o in bpy.data.objects))}")
            required = {"leg": leg_glb, "yarns": yarn_glb, "stocking": surface_glb}
            for node in GLB_NODES:
                if node in meshes:
                    check_object(checks, f"glb.{node}", node, meshes[node], required[node],
                                 world=False, loose_edges=node == "yarns", samples=args.samples)
            if "stocking" in meshes:
                check_stocking_material(checks, path)

    # --- leg.ply, stocking.ply
    for fname, obj_name, required, edges in (
        ("leg.ply", "leg", leg_ply, False),
        ("stocking.ply", "stocking", [ply_name(a) for a in yarn_required], True),
    ):
        path = paths[fname]
        print(f"\n{path}: bpy.ops.wm.ply_import (forward_axis='NEGATIVE_Z', up_axis='Y', "
              "merge_verts=False, import_attributes=True)")
        label = "ply." + fname.removesuffix(".ply")
        try:
            fm = ply_mesh(path, obj_name)
        except Exception as err:  # noqa: BLE001
            checks.check(f"{label}.read", False, f"{type(err).__name__}: {err}")
            continue
        if edges:
            check_report_counts(checks, label, fm, report)
        fresh_blender()
        if run_import(checks, label, lambda: bpy.ops.wm.ply_import(
                filepath=path, forward_axis="NEGATIVE_Z", up_axis="Y")):
            check_object(checks, label, obj_name, fm, required, world=True, loose_edges=edges,
                         samples=args.samples)

    print()
    if checks.failed:
        print(f"FAILED {len(checks.failed)} of {checks.count} checks: {', '.join(checks.failed)}")
        return 1
    print(f"all {checks.count} checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
