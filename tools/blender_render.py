"""Render a knitfit ``stocking.glb`` as Blender 4.5 shows it: its glTF importer with the defaults,
the file's own materials, Cycles on the CPU; with the camera and lights of a camera.json from
``tools/client_pixels.py camera`` (issue 23's client check; three.js draws the same in
tools/client_render/).

    tools/.venv-blender/bin/python tools/blender_render.py CAMERA_JSON GLB OUT_DIR [--samples N]

Writes OUT_DIR/{dressed,bare,black_leg,leg,stocking}.png (what each is: tools/client_pixels.py).
Exit 0 when all five were written, 1 when the import or a render failed, 2 on bad arguments.

Matching three.js: the camera is a perspective camera with ``sensor_fit`` VERTICAL and the vertical
field of view of the JSON (three.js's ``fov`` is vertical too); it looks along -Z with +Y up in
the file's frame, which the importer turns into Blender's (x, y, z) -> (x, -z, y). The sun
(strength = its irradiance, as a three.js DirectionalLight's intensity) casts no shadows, as
three.js draws none unless asked; the world is a uniform colour of the JSON's radiance (three.js:
an ambient light, see client_pixels.py), with no diffuse or glossy bounces (three.js has no
interreflection), view transform Standard (three.js: NoToneMapping, sRGB output). Masks are the
node alone with a white emission material on a black world.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

try:
    import bpy
    from mathutils import Matrix, Vector
except ImportError:  # pragma: no cover - run with the bpy venv
    print("blender_render: needs the bpy module (tools/.venv-blender, see the module doc)",
          file=sys.stderr)
    sys.exit(2)

RENDERS = ("dressed", "bare", "black_leg", "leg", "stocking")


def blender_from_file(v) -> Vector:
    """A glTF (file-frame) point or direction in Blender's frame, as the importer converts it."""
    x, y, z = v
    return Vector((x, -z, y))


def quiet(fn):
    """Runs fn with the C-level stdout/stderr (Cycles, the importer) sent to /dev/null."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    os.dup2(null, 2)
    try:
        return fn()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)


def emission(name: str, colour: float) -> bpy.types.Material:
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    em = nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (colour, colour, colour, 1)
    em.inputs["Strength"].default_value = 1.0
    out = nodes.new("ShaderNodeOutputMaterial")
    mat.node_tree.links.new(em.outputs["Emission"], out.inputs["Surface"])
    return mat


def setup_scene(cam: dict, samples: int) -> tuple[bpy.types.Object, bpy.types.Object]:
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.max_bounces = 8
    scene.cycles.diffuse_bounces = 0
    scene.cycles.glossy_bounces = 0
    scene.cycles.transmission_bounces = 0
    scene.cycles.volume_bounces = 0
    scene.cycles.transparent_max_bounces = 16
    scene.cycles.filter_width = 1.0
    scene.cycles.seed = 0
    scene.render.resolution_x = cam["width"]
    scene.render.resolution_y = cam["height"]
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1
    scene.render.film_transparent = False
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.color_depth = "8"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0
    scene.view_settings.gamma = 1
    scene.display_settings.display_device = "sRGB"

    world = bpy.data.worlds.new("client_world")
    world.use_nodes = True
    scene.world = world

    data = bpy.data.cameras.new("client_camera")
    data.type = "PERSP"
    data.sensor_fit = "VERTICAL"
    data.sensor_height = 24.0
    data.lens = data.sensor_height / 2 / math.tan(math.radians(cam["vfov_deg"]) / 2)
    data.clip_start, data.clip_end = cam["near"], cam["far"]
    camera = bpy.data.objects.new("client_camera", data)
    scene.collection.objects.link(camera)
    eye, target, up = (blender_from_file(cam[k]) for k in ("eye", "target", "up"))
    back = (eye - target).normalized()  # the camera's +Z
    right = up.cross(back).normalized()
    true_up = back.cross(right)
    rot = Matrix((right, true_up, back)).transposed()
    camera.matrix_world = Matrix.Translation(eye) @ rot.to_4x4()
    scene.camera = camera

    sun_data = bpy.data.lights.new("client_sun", "SUN")
    sun_data.energy = cam["sun_irradiance"]
    sun_data.angle = 0.0
    sun_data.use_shadow = False
    if hasattr(sun_data, "cycles") and hasattr(sun_data.cycles, "cast_shadow"):
        sun_data.cycles.cast_shadow = False
    sun = bpy.data.objects.new("client_sun", sun_data)
    scene.collection.objects.link(sun)
    to_light = blender_from_file(cam["sun_direction_to_light"]).normalized()
    # A sun shines along its local -Z.
    sun.rotation_euler = to_light.to_track_quat("Z", "Y").to_euler()
    return camera, sun


def set_world(colour: float) -> None:
    bg = bpy.context.scene.world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (colour, colour, colour, 1)
    bg.inputs["Strength"].default_value = 1.0


def projection_error(cam: dict, camera: bpy.types.Object) -> float:
    """Largest pixel distance between Blender's projection of the frame box's corners and
    client_pixels.project's (which three.js's camera follows): the cameras agree."""
    from bpy_extras.object_utils import world_to_camera_view
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import client_pixels  # noqa: E402 - next to this file
    import numpy as np
    lo, hi = cam["frame_box"]["min"], cam["frame_box"]["max"]
    corners = [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    ours = client_pixels.project(cam, np.array(corners))
    worst = 0.0
    scene = bpy.context.scene
    for p, q in zip(corners, ours):
        v = world_to_camera_view(scene, camera, blender_from_file(p))
        px = (v.x * cam["width"], (1 - v.y) * cam["height"])
        worst = max(worst, math.hypot(px[0] - q[0], px[1] - q[1]))
    return worst


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("camera")
    parser.add_argument("glb")
    parser.add_argument("out_dir")
    parser.add_argument("--samples", type=int, default=16,
                        help="Cycles samples of the shaded renders (default 16; the render over a black "
                             "leg takes 4 times as many, masks 4)")
    args = parser.parse_args(argv)
    with open(args.camera, encoding="utf-8") as f:
        cam = json.load(f)
    os.makedirs(args.out_dir, exist_ok=True)

    t0 = time.time()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    try:
        result = quiet(lambda: bpy.ops.import_scene.gltf(filepath=os.path.abspath(args.glb)))
    except Exception as err:  # noqa: BLE001 - an importer failure is the client's verdict
        print(f"blender_render: import of {args.glb} failed: {type(err).__name__}: {err}")
        return 1
    if result != {"FINISHED"}:
        print(f"blender_render: import of {args.glb} returned {result}")
        return 1
    t_import = time.time() - t0
    objects = {o.name: o for o in bpy.data.objects if o.type == "MESH"}
    nodes = {n: objects.get(n) for n in ("leg", "yarns", "stocking")}
    shown = [o.name for o in bpy.context.scene.objects if o.visible_get()]
    camera, _sun = setup_scene(cam, args.samples)
    err = projection_error(cam, camera)
    print(f"Blender {bpy.app.version_string}: imported {', '.join(sorted(objects))} in "
          f"{t_import:.1f} s (shown: {', '.join(sorted(shown))}); camera projection vs "
          f"client_pixels: {err:.3f} px")

    own = {o: [s.material for s in o.material_slots] for o in objects.values()}
    white, black = emission("client_white", 1.0), emission("client_black", 0.0)
    scene = bpy.context.scene

    def restore() -> None:
        for o, mats in own.items():
            o.hide_render = False
            for slot, m in zip(o.material_slots, mats):
                slot.material = m
        set_world(cam["world_radiance"])
        scene.cycles.samples = args.samples
        bpy.data.objects["client_sun"].hide_render = False

    def override(obj, mat) -> None:
        if obj is None:
            return
        if not obj.material_slots:
            obj.data.materials.append(mat)
            own[obj].append(None)
        for slot in obj.material_slots:
            slot.material = mat

    for mode in RENDERS:
        restore()
        if mode == "bare":
            for n in ("stocking", "yarns"):
                if nodes[n] is not None:
                    nodes[n].hide_render = True
        elif mode == "black_leg":
            override(nodes["leg"], black)
            # Cycles draws alpha by stochastic transparency: at 16 samples a sheer stocking
            # over black is speckled with dark pixels the streak check would count. The black
            # leg is unlit, so four times the samples cost less than the dressed render.
            scene.cycles.samples = 4 * args.samples
            if nodes["yarns"] is not None:
                nodes["yarns"].hide_render = True
        elif mode in ("leg", "stocking"):
            for n, o in nodes.items():
                if o is not None:
                    o.hide_render = n != mode
            override(nodes[mode], white)
            set_world(0.0)
            bpy.data.objects["client_sun"].hide_render = True
            scene.cycles.samples = 4
        scene.render.filepath = os.path.join(os.path.abspath(args.out_dir), f"{mode}.png")
        t = time.time()
        try:
            quiet(lambda: bpy.ops.render.render(write_still=True))
        except Exception as err:  # noqa: BLE001
            print(f"blender_render: render {mode} failed: {type(err).__name__}: {err}")
            return 1
        print(f"  {mode}: {scene.cycles.samples} samples, {time.time() - t:.1f} s")
    # Objects given an extra slot for a mask keep it; nothing is saved.
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
