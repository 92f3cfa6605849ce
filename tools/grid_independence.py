#!/usr/bin/env python3
"""Grid independence of the leg's fields (issue 21, docs/decisions/0059): fits each sample leg at
several grids and prints, per grid, the relative L2 difference of `_STITCH_DENSITY`, `_COVERAGE`
and `_PRESSURE` on the covered leg vertices against a reference fit (the real stitch count, by
default at a tight tolerance): over the whole leg; over the vertices above the ankle; over the
whole leg but the toe box (beyond the rim the report gives in `details.tube.toe_box`, where the
fabric rests on the toes boxed: on the samples' feet 57-63 % of the covered vertices; decision 0064);
and over the whole leg with each vertex weighted by its share of the skin's area (per vertex, a
finely meshed foot's toes weigh more than the rest of the leg).

    python3 tools/grid_independence.py --out /tmp/gi                       # every sample leg
    python3 tools/grid_independence.py --out /tmp/gi --samples makehuman_leg_foot \\
        --grids 150,150x150,300x300 --tolerance 1e-3 --reference-tolerance 3e-5

A grid of wales alone (`150`) leaves the courses to the stitch, as the default scene does.

Fits already in --out are reused (delete the folder to refit). Standard library only; needs a
release build (`cargo build --release`). The real count's fit can take minutes at 3e-5.
"""

import argparse
import json
import math
import pathlib
import struct
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
SAMPLES = ["procedural_leg", "makehuman_leg", "lowpoly_leg", "makehuman_leg_foot",
           "makehuman_body", "makehuman_hips_heavy"]
FIELDS = ["stitch_density", "coverage", "pressure"]
PLY_TYPES = {"float": "f", "uchar": "B", "int": "i", "uint": "I"}


def read_leg_ply(path):
    """The vertices of a binary little-endian leg.ply (a list of dicts of their properties) and
    its faces (lists of vertex indices)."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    count, faces, props, in_vertex = 0, 0, [], False
    for line in data[:end].decode().splitlines():
        words = line.split()
        if words[:2] == ["element", "vertex"]:
            count, in_vertex = int(words[2]), True
        elif words[:2] == ["element", "face"]:
            faces, in_vertex = int(words[2]), False
        elif words[:1] == ["element"]:
            in_vertex = False
        elif in_vertex and words[:1] == ["property"]:
            props.append((words[2], PLY_TYPES[words[1]]))
    record = struct.Struct("<" + "".join(t for _, t in props))
    names = [n for n, _ in props]
    vertices = [dict(zip(names, record.unpack_from(data, end + k * record.size)))
                for k in range(count)]
    polygons, at = [], end + count * record.size
    for _ in range(faces):
        corners = data[at]
        polygons.append(struct.unpack_from(f"<{corners}i", data, at + 1))
        at += 1 + 4 * corners
    return vertices, polygons


def vertex_areas(vertices, faces):
    """Each vertex's share of the skin: a third of the area of each triangle on it (polygons
    fanned from their first corner)."""
    areas = [0.0] * len(vertices)
    point = lambda i: (vertices[i]["x"], vertices[i]["y"], vertices[i]["z"])
    for face in faces:
        for j in range(1, len(face) - 1):
            corners = (face[0], face[j], face[j + 1])
            a, b, c = (point(i) for i in corners)
            u = [q - p for p, q in zip(a, b)]
            v = [q - p for p, q in zip(a, c)]
            cross = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                     u[0] * v[1] - u[1] * v[0])
            third = math.sqrt(sum(x * x for x in cross)) / 6.0
            for i in corners:
                areas[i] += third
    return areas


def fit(binary, scene, leg, grid, tolerance, out):
    """Fits `leg` at `grid` into `out` unless its report is there; returns the report."""
    report = out / "report.json"
    if not report.exists():
        out.mkdir(parents=True, exist_ok=True)
        command = [str(binary), "fit", str(scene), "--leg", str(leg), "--resolution", grid,
                   "--tolerance", str(tolerance), "-q", "--out", str(out)]
        run = subprocess.run(command, capture_output=True, text=True)
        # Exit 3: written, but not converged within solver.max_steps; say so and use it.
        if run.returncode not in (0, 3):
            sys.exit(f"{' '.join(command)}: exit {run.returncode}: {run.stderr.strip()}")
        if run.returncode == 3:
            print(f"warning: {grid} at {tolerance:g} did not converge", file=sys.stderr)
    return json.loads(report.read_text())


def relative_l2(vertices, reference, field, weights):
    """Relative L2 difference in %, each vertex weighted (0 leaves it out)."""
    num = sum(w * (v[field] - r[field]) ** 2 for v, r, w in zip(vertices, reference, weights))
    den = sum(w * r[field] ** 2 for r, w in zip(reference, weights))
    return 100.0 * math.sqrt(num / den) if den > 0 else float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, type=pathlib.Path)
    parser.add_argument("--samples", default=",".join(SAMPLES))
    # Wales alone: courses that make each cell as many stitches long as wide (decision 0069).
    parser.add_argument("--grids", default="100,150,300,100x100,150x150,300x300")
    parser.add_argument("--tolerance", type=float, default=1e-3)
    parser.add_argument("--reference-tolerance", type=float, default=3e-5)
    parser.add_argument("--binary", type=pathlib.Path, default=ROOT / "target/release/knitfit")
    args = parser.parse_args()

    scene = json.loads((ROOT / "samples/scene.json").read_text())
    scene["outputs"] = ["ply"]
    args.out.mkdir(parents=True, exist_ok=True)
    scene_path = args.out / "scene.json"
    scene_path.write_text(json.dumps(scene))

    for sample in args.samples.split(","):
        leg = ROOT / "samples" / f"{sample}.glb"
        here = args.out / sample
        first = fit(args.binary, scene_path, leg, "150x150", args.tolerance,
                    here / f"150x150_{args.tolerance:g}")
        knit = first["details"]["knit"]
        real = f"{round(knit['needles'])}x{round(knit['courses']) + 1}"
        ref_report = fit(args.binary, scene_path, leg, real, args.reference_tolerance,
                         here / f"{real}_{args.reference_tolerance:g}")
        reference, faces = read_leg_ply(here / f"{real}_{args.reference_tolerance:g}" / "leg.ply")
        areas = vertex_areas(reference, faces)
        marks = ref_report["details"]["leg"]["landmarks"]
        up = marks["up"]
        height = lambda p: sum(a * b for a, b in zip(p, up))
        ankle = height(marks["ankle"]["centre"]["m"]) if marks.get("ankle") else -math.inf
        covered = [r["coverage"] > 0 for r in reference]
        above = [c and height((r["x"], r["y"], r["z"])) >= ankle
                 for c, r in zip(covered, reference)]
        toe_box = [False] * len(reference)
        if box := ref_report["details"]["tube"].get("toe_box"):
            rim, forward = box["rim_centre_m"], box["towards_toe"]
            beyond = lambda r: sum((p - c) * f for p, c, f in
                                   zip((r["x"], r["y"], r["z"]), rim, forward)) > 0
            toe_box = [c and beyond(r) for c, r in zip(covered, reference)]
        no_toes = [c and not t for c, t in zip(covered, toe_box)]
        print(f"\n{sample}: against {real} at {args.reference_tolerance:g}; "
              f"{sum(covered)} covered vertices, {sum(above)} above the ankle, "
              f"{sum(toe_box)} in the toe box")
        print("| grid (tolerance) | density | coverage | pressure | above the ankle: "
              "density / coverage / pressure | without the toe box | by area: "
              "density / coverage / pressure | seconds |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|")
        for grid in args.grids.split(","):
            out = here / f"{grid}_{args.tolerance:g}"
            report = fit(args.binary, scene_path, leg, grid, args.tolerance, out)
            vertices, _ = read_leg_ply(out / "leg.ply")
            whole = [relative_l2(vertices, reference, f, covered) for f in FIELDS]
            leg_only = [relative_l2(vertices, reference, f, above) for f in FIELDS]
            toeless = [relative_l2(vertices, reference, f, no_toes) for f in FIELDS]
            by_area = [relative_l2(vertices, reference, f, [a * c for a, c in zip(areas, covered)])
                       for f in FIELDS]
            tube = report["details"]["tube"]
            name = grid if "x" in grid else f"{grid}: {tube['wales']}x{tube['courses']}"
            print(f"| {name} ({args.tolerance:g}) | " + " | ".join(f"{e:.1f} %" for e in whole)
                  + "".join(" | " + " / ".join(f"{e:.1f}" for e in columns) + " %"
                            for columns in (leg_only, toeless, by_area))
                  + " | "
                  + f"{report['wall_seconds']:.2f} |")


if __name__ == "__main__":
    main()
