#!/usr/bin/env python3
"""A second body model for the samples and the leg zoo: Meta's Momentum Human Rig (MHR, Apache-2.0).

MHR is a parametric body model built from its own scans (arXiv 2511.15586), independent of the
MakeHuman mesh the other samples are cut from. Its repository, github.com/facebookresearch/MHR,
holds three meshes of its 18,439-vertex LOD 1 topology without the model's downloadable assets:
- tools/mhr_smpl_conversion/assets/mhr_face_mask.ply: the neutral body at rest, a T-pose, in
  centimetres, +Y up, facing +Z, its left on +X (the colours mark the face; they are dropped);
- tools/mhr_smpl_conversion/data/sam3d_body_outputs/img_subj0N.npz: bodies SAM 3D Body fitted
  to photographs, `pred_vertices` in the camera's frame (metres, +Y down, +Z away from the camera,
  so the person faces -Z), sharing the rest mesh's triangles.

This script writes, each one closed mesh of 36,874 triangles, metres, +Y up, facing +Z, the lowest
point at y = 0:
- samples/mhr/body.glb: the rest body (T-pose);
- samples/mhr/arms_raised.glb: subject 2, standing with its feet apart, knees a little bent and
  both arms raised over the head;
- samples/mhr/one_leg.glb: subject 1, standing on its left leg, the right knee raised, arms up;
- samples/mhr/kneeling.glb: subject 0, kneeling, its hands bent flat over its head (read upside
  down, the hands look like feet).

Run (from the repository root; the MHR checkout at commit 5deda6a69f30019915ded6299c7aab74acaca57f):
    python3 -m venv tools/.venv
    tools/.venv/bin/pip install numpy==2.2.6 trimesh==4.6.8
    tools/.venv/bin/python tools/mhr_samples.py --mhr PATH/TO/MHR
"""

import argparse
from pathlib import Path

import numpy as np
import trimesh

REST = "tools/mhr_smpl_conversion/assets/mhr_face_mask.ply"
POSED = "tools/mhr_smpl_conversion/data/sam3d_body_outputs/img_subj0{}.npz"


def read_rest(mhr):
    """The rest mesh's vertices (cm) and triangles from its binary PLY (x, y, z, RGBA; lists)."""
    raw = (mhr / REST).read_bytes()
    body = raw.index(b"end_header\n") + len(b"end_header\n")
    header = raw[:body].decode("ascii").split("\n")
    count = {line.split()[1]: int(line.split()[2]) for line in header if line.startswith("element")}
    vertex = np.dtype([("p", "<f4", 3), ("rgba", "u1", 4)])
    face = np.dtype([("n", "u1"), ("i", "<i4", 3)])
    vertices = np.frombuffer(raw, vertex, count["vertex"], body)["p"]
    faces = np.frombuffer(raw, face, count["face"], body + count["vertex"] * vertex.itemsize)
    assert (faces["n"] == 3).all(), "the rest mesh is triangles"
    return vertices.astype(np.float64), faces["i"].astype(np.int64)


def posed(mhr, subject):
    """A photographed subject's vertices turned from the camera's frame to +Y up, facing +Z."""
    vertices = np.load(mhr / POSED.format(subject))["pred_vertices"].astype(np.float64)
    return vertices * np.array([1.0, -1.0, -1.0])  # half a turn about X


def write(path, vertices, triangles):
    vertices = vertices - np.array([0.0, vertices[:, 1].min(), 0.0])
    mesh = trimesh.Trimesh(vertices, triangles, process=False)
    assert mesh.is_watertight, f"{path}: the body is one closed skin"
    mesh.export(path)
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    print(f"{path}: {len(triangles)} triangles, {np.round(high - low, 3)} m")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mhr", type=Path, required=True, help="a checkout of facebookresearch/MHR")
    parser.add_argument("--out", type=Path, default=Path("samples/mhr"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rest, triangles = read_rest(args.mhr)
    write(args.out / "body.glb", rest / 100.0, triangles)
    write(args.out / "arms_raised.glb", posed(args.mhr, 2), triangles)
    write(args.out / "one_leg.glb", posed(args.mhr, 1), triangles)
    write(args.out / "kneeling.glb", posed(args.mhr, 0), triangles)


if __name__ == "__main__":
    main()
