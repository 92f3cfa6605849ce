"""Import samples/rigged/makehuman_rigged*.glb into Blender (bpy as a Python module) and pose the left knee.

Setup: the venv of tools/blender_check.py (``python3.11 -m venv tools/.venv-blender &&
tools/.venv-blender/bin/pip install -r tools/blender_requirements.txt``, bpy==4.5.15).

Run (from the repository root)::

    tools/.venv-blender/bin/python tools/blender_rig_check.py [samples/rigged/makehuman_rigged.glb]
                                                             [samples/rigged/makehuman_rigged_walk.glb]

Checks, each from an empty Blender file and ``bpy.ops.import_scene.gltf`` with its defaults:
the rest file makes one armature with the 52 "mixamorig:" bones and a mesh "body" with one
vertex group per bone and an Armature modifier; its evaluated (skinned) vertices are the file's
positions; posing mixamorig:LeftLeg by 60 degrees about its own X axis (Blender's bone frame,
printed) moves the vertices weighted to mixamorig:LeftFoot and leaves the right leg still. The
walk file, whose joint nodes carry the pose, evaluates to the positions tools/makehuman_rigged.py
computes by linear blend skinning. Positions are compared in the file's frame: Blender (x, y, z)
is file (x, z, -y). Exit status 1 if a check fails.
"""

import math
import sys
from pathlib import Path

import bpy
import numpy as np

FAILED = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILED.append(what)


def load(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=str(path))
    arms = [o for o in bpy.data.objects if o.type == "ARMATURE"]
    body = bpy.data.objects.get("body")
    return arms, body


def evaluated(body):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    mesh = body.evaluated_get(depsgraph).to_mesh()
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    world = np.array(body.matrix_world)
    co = co @ world[:3, :3].T + world[:3, 3]
    body.evaluated_get(depsgraph).to_mesh_clear()
    return np.c_[co[:, 0], co[:, 2], -co[:, 1]]  # Blender Z-up -> file Y-up


def read_skin(path):
    """The file's skinned mesh (json + struct, no glTF library): POSITION, JOINTS_0, WEIGHTS_0, the
    joint names, and the positions linear blend skinning gives with the nodes' global matrices."""
    import json
    import struct

    data = Path(path).read_bytes()
    json_len = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + json_len])
    blob = data[20 + json_len + 8 :]
    node = next(n for n in doc["nodes"] if "skin" in n)
    prim = doc["meshes"][node["mesh"]]["primitives"][0]

    def acc(i, dtype, n):
        a = doc["accessors"][i]
        v = doc["bufferViews"][a["bufferView"]]
        return np.frombuffer(blob, dtype, a["count"] * n, v.get("byteOffset", 0) + a.get("byteOffset", 0)).reshape(-1, n)

    skin = doc["skins"][node["skin"]]
    names = [doc["nodes"][j]["name"] for j in skin["joints"]]
    a = prim["attributes"]
    pos, joints, weights = acc(a["POSITION"], np.float32, 3), acc(a["JOINTS_0"], np.uint8, 4), acc(a["WEIGHTS_0"], np.float32, 4)

    glob = {}

    def walk(i, parent):
        n = doc["nodes"][i]
        x, y, z, w = n.get("rotation", [0.0, 0.0, 0.0, 1.0])
        local = np.eye(4)
        local[:3, :3] = [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
        local[:3, 3] = n.get("translation", [0.0, 0.0, 0.0])
        glob[i] = parent @ local
        for c in n.get("children", []):
            walk(c, glob[i])

    for root in doc["scenes"][doc.get("scene", 0)]["nodes"]:
        walk(root, np.eye(4))
    ibm = acc(skin["inverseBindMatrices"], np.float32, 16).astype(float).reshape(-1, 4, 4).transpose(0, 2, 1)
    palette = np.array([glob[j] @ ibm[k] for k, j in enumerate(skin["joints"])])
    skinned = np.einsum("vk,vkij,vj->vi", weights.astype(float), palette[joints], np.c_[pos, np.ones(len(pos))])[:, :3]
    return pos, joints, weights, names, skinned


def main():
    rest_path = Path(sys.argv[1] if len(sys.argv) > 1 else "samples/rigged/makehuman_rigged.glb")
    walk_path = Path(sys.argv[2] if len(sys.argv) > 2 else "samples/rigged/makehuman_rigged_walk.glb")
    stored, joints, weights, names, _ = read_skin(rest_path)

    arms, body = load(rest_path)
    check(len(arms) == 1, f"{rest_path}: one armature ({[a.name for a in arms]})")
    arm = arms[0]
    bones = [b.name for b in arm.data.bones]
    check(len(bones) == 52 and all(b.startswith("mixamorig:") for b in bones), f"52 mixamorig bones ({len(bones)})")
    check(body is not None and body.type == "MESH", "a mesh object 'body'")
    groups = [g.name for g in body.vertex_groups]
    mods = [(m.type, m.object.name if m.object else None) for m in body.modifiers]
    print(f"     body: {len(body.data.vertices)} vertices, {len(body.data.polygons)} faces, "
          f"{len(groups)} vertex groups, modifiers {mods}, parent {body.parent.name if body.parent else None}")
    check(len(groups) == 52 and set(groups) == set(bones), "one vertex group per bone")
    check(("ARMATURE", arm.name) in mods, "an Armature modifier on the armature")
    # The importer adds a mesh "Icosphere" as the bones' display shape; it is not ours.
    shapes = {pb.custom_shape.name for pb in arm.pose.bones if pb.custom_shape}
    print(f"     bone display shapes made by the importer: {sorted(shapes)}")
    others = sorted(
        (o.name, o.parent.name if o.parent else None, o.parent_bone)
        for o in bpy.context.scene.objects
        if o.type == "MESH" and o.name != "body" and o.name not in shapes
    )
    print(f"     other meshes (name, parent, parent bone): {others}")
    check(len(others) == 7 and all(o[1:] == (arm.name, "mixamorig:Head") for o in others), "7 small parts on mixamorig:Head")
    check(len(body.data.vertices) == len(stored), "Blender keeps the file's vertices")
    rest = evaluated(body)
    check(np.abs(rest - stored).max() < 1e-5, f"skinned at rest = the file's positions (max {np.abs(rest - stored).max():.2e} m)")

    pose_bone = arm.pose.bones["mixamorig:LeftLeg"]
    m = arm.matrix_world @ pose_bone.bone.matrix_local
    x_axis = np.array(m.col[0][:3])
    y_axis = np.array(m.col[1][:3])
    to_file = lambda v: np.array([v[0], v[2], -v[1]])  # noqa: E731
    print(f"     mixamorig:LeftLeg in Blender: head {np.round(to_file(np.array(pose_bone.bone.head_local)), 4)} (file frame), "
          f"local X = file {np.round(to_file(x_axis), 3)}, local Y (along the bone) = file {np.round(to_file(y_axis), 3)}")
    pose_bone.rotation_mode = "XYZ"
    pose_bone.rotation_euler = (math.radians(60.0), 0.0, 0.0)
    bpy.context.view_layer.update()
    bent = evaluated(body)
    foot = names.index("mixamorig:LeftFoot")
    on_foot = (joints[:, 0] == foot) & (weights[:, 0] > 0.9)
    move = (bent - rest)[on_foot]
    print(f"     LeftLeg +60 deg about its local X: {on_foot.sum()} vertices on LeftFoot moved by "
          f"{np.round(move.mean(axis=0), 4)} m on average (file frame x y z), |move| {np.linalg.norm(move, axis=1).min():.3f}..{np.linalg.norm(move, axis=1).max():.3f} m")
    check(np.linalg.norm(move, axis=1).min() > 0.1, "the left ankle's vertices move (> 0.1 m each)")
    check(move[:, 1].mean() > 0.05, "... and rise")
    right = np.linalg.norm(bent - rest, axis=1)[stored[:, 0] < -0.05]
    print(f"     right side (x < -0.05): {(right > 1e-6).sum()} vertices moved, at most {right.max():.2e} m")
    check(right.max() < 0.005, "the right leg stays (bar MPFB's stray weights)")

    arms, body = load(walk_path)
    walk = evaluated(body)
    *_, expected = read_skin(walk_path)
    d = np.abs(walk - expected).max()
    check(d < 1e-4, f"{walk_path}: Blender's posed mesh = linear blend skinning of the file (max {d:.2e} m)")
    ankle = (walk - stored)[on_foot].mean(axis=0)
    print(f"     walk: LeftFoot vertices moved by {np.round(ankle, 4)} m on average from rest")
    if FAILED:
        print(f"{len(FAILED)} checks failed: {FAILED}")
        sys.exit(1)
    print("all checks passed")


if __name__ == "__main__":
    main()
