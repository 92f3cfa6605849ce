"""The camera and the pixel checks of the client renders (issue 23): a fit's ``stocking.glb`` as
three.js (tools/client_render/) and Blender (tools/blender_render.py) draw it, checked by one
set of numpy rules for both.

Two commands, run with the bpy venv's Python (it has numpy)::

    tools/.venv-blender/bin/python tools/client_pixels.py camera FIT_DIR CAMERA_JSON
    tools/.venv-blender/bin/python tools/client_pixels.py check CASE_DIR

``camera`` reads FIT_DIR/stocking.glb (and report.json's landmarks) and writes the one camera and
light setup both clients render with. ``check`` reads CASE_DIR/camera.json and, for each client
directory CASE_DIR/threejs and CASE_DIR/blender, the five PNGs every client writes:

=================  =====================================================================
``dressed.png``    the file as it is (every node, the file's own materials)
``bare.png``       the same with the ``stocking`` and ``yarns`` nodes hidden: the bare leg
``black_leg.png``  the stocking surface alone over the leg drawn black (unlit; yarns hidden):
                   what the stocking itself adds, for its transmittance, and where the leg
                   wins the depth test
``leg.png``        mask: the ``leg`` node alone, flat white on black
``stocking.png``   mask: the ``stocking`` node alone, flat white on black
=================  =====================================================================

It prints every figure and one ``FAIL case/client check: why`` line per failed check, and exits
1 if any failed (0 if none; 2 on bad input).

Camera (same for both clients): a front view (from +Z, the glTF character's front; +Y up) of the
bounding box of the ``stocking`` node (the ``leg`` node's if there is none, so a whole body is
framed on its dressed leg), grown by a tenth of its height above and below so skin beyond the
stocking's ends is in the picture; perspective, vertical field of view ``VFOV_DEG``; distance such
that the box's front face fits with a margin. Lights: a sun (directional, no shadows) from the
camera's side, a little above and to the right, and a uniform world of radiance ``WORLD`` (in
three.js an ambient light of intensity pi * WORLD: three.js's ambient irradiance is its
intensity, a uniform world's is pi times its radiance; its directional light's intensity is the
sun's irradiance, as Blender's sun strength is). The background is that world's colour. Output
sRGB, no tone mapping (three.js NoToneMapping; Blender view transform Standard).
"""

from __future__ import annotations

import json
import math
import os
import struct
import sys

import numpy as np

WIDTH, HEIGHT = 200, 400
VFOV_DEG = 30.0
#: Linear radiance of the uniform world (and the background's linear grey).
WORLD = 0.25
#: The sun's irradiance (Blender sun strength, three.js DirectionalLight intensity).
SUN = 2.0

# --- thresholds (sRGB luma 0-1 unless said)
#: A skin pixel darker than this is "near-black" (the dimmest lit skin under this setup, albedo
#: 0.3 lit by the world alone, is 0.3 * 0.25 = 0.075 linear, 0.30 sRGB).
BLACK_LUMA = 0.1
#: Largest share of near-black skin pixels.
MAX_BLACK_SHARE = 0.005
#: A calf pixel is a streak when it departs from its neighbourhood's median by more than this.
STREAK_CONTRAST = 0.05
#: Side of the square neighbourhood, in pixels.
STREAK_WINDOW = 9
#: Largest share of streak pixels in the calf.
MAX_STREAK_SHARE = 0.01
#: The stocking must change the calf's colour by at least this much (mean RGB distance, sRGB).
MIN_VISIBLE_DELTA = 0.03
#: The calf's mean transmittance (skin seen through the stocking) must lie between these.
MIN_TRANSMITTANCE, MAX_TRANSMITTANCE = 0.3, 0.97
#: The calf's column profile with the stocking must correlate this well with the bare one.
MIN_PROFILE_CORR = 0.8
#: "Stocking over skin": pixels where the dressed render's luma differs from the bare one's by
#: more than this.
COVERED_DELTA = 0.01
#: IoU the two clients' leg silhouettes and "stocking over skin" regions must reach.
MIN_LEG_IOU, MIN_COVERED_IOU = 0.97, 0.85
#: Pixels a region keeps from the silhouette's edge (antialiasing, rim).
EDGE = 3
#: The calf: this fraction of the way from the ankle up to the knee ...
CALF_FROM, CALF_TO = 0.25, 0.75

CLIENTS = ("threejs", "blender")
RENDERS = ("dressed", "bare", "black_leg", "leg", "stocking")


# ------------------------------------------------------------------ GLB and camera

def read_glb_json(path: str) -> dict:
    """The JSON chunk of a .glb."""
    with open(path, "rb") as f:
        head = f.read(20)
        magic, _version, _length, json_len, json_type = struct.unpack("<4sIIII", head)
        if magic != b"glTF" or json_type != 0x4E4F534A:
            raise ValueError(f"{path}: not a GLB with a JSON chunk")
        return json.loads(f.read(json_len))


def node_world_matrices(doc: dict) -> dict[int, np.ndarray]:
    """World matrix (4x4, column vectors) of every node reachable from the default scene."""
    def local(node: dict) -> np.ndarray:
        if "matrix" in node:
            return np.array(node["matrix"], dtype=float).reshape(4, 4).T
        t = np.array(node.get("translation", [0, 0, 0]), dtype=float)
        x, y, z, w = node.get("rotation", [0, 0, 0, 1])
        r = np.array([
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ])
        s = np.array(node.get("scale", [1, 1, 1]), dtype=float)
        m = np.eye(4)
        m[:3, :3] = r * s
        m[:3, 3] = t
        return m

    out: dict[int, np.ndarray] = {}

    def walk(i: int, parent: np.ndarray) -> None:
        out[i] = parent @ local(doc["nodes"][i])
        for c in doc["nodes"][i].get("children", []):
            walk(c, out[i])

    scene = doc.get("scenes", [{}])[doc.get("scene", 0)]
    for i in scene.get("nodes", []):
        walk(i, np.eye(4))
    return out


def node_bounds_world(doc: dict, name: str) -> tuple[np.ndarray, np.ndarray] | None:
    """World-space bounding box of a named node's mesh (the POSITION accessors' min/max, which
    glTF requires, carried through the node's world matrix), or None if there is no such node."""
    mats = node_world_matrices(doc)
    for i, node in enumerate(doc["nodes"]):
        if node.get("name") != name or "mesh" not in node or i not in mats:
            continue
        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        for prim in doc["meshes"][node["mesh"]]["primitives"]:
            acc = doc["accessors"][prim["attributes"]["POSITION"]]
            a, b = np.array(acc["min"], float), np.array(acc["max"], float)
            corners = np.array([[x, y, z, 1] for x in (a[0], b[0]) for y in (a[1], b[1])
                                for z in (a[2], b[2])])
            world = (mats[i] @ corners.T).T[:, :3]
            lo, hi = np.minimum(lo, world.min(0)), np.maximum(hi, world.max(0))
        return lo, hi
    return None


def landmark(report: dict, name: str) -> list[float] | None:
    """A landmark's centre in the file's frame (report.json details.leg.landmarks)."""
    try:
        return report["details"]["leg"]["landmarks"][name]["centre"]["file"]
    except (KeyError, TypeError):
        return None


def make_camera(glb_path: str, report_path: str | None) -> dict:
    """The camera and lights both clients render with (see the module doc)."""
    doc = read_glb_json(glb_path)
    box = node_bounds_world(doc, "stocking") or node_bounds_world(doc, "leg")
    if box is None:
        raise ValueError(f"{glb_path}: no 'stocking' or 'leg' node with a mesh")
    lo, hi = box
    grow = 0.1 * (hi[1] - lo[1])
    lo, hi = lo - [0, grow, 0], hi + [0, grow, 0]
    target = (lo + hi) / 2
    aspect = WIDTH / HEIGHT
    t = math.tan(math.radians(VFOV_DEG) / 2)
    half_w, half_h, half_d = (hi - lo) / 2
    dist = max(half_h / t, half_w / (t * aspect)) * 1.05 + half_d
    eye = target + [0, 0, dist]
    # Sun from the camera's side, a little above and to the right of it.
    to_sun = np.array([0.3, 0.4, 1.0])
    to_sun /= np.linalg.norm(to_sun)
    cam = {
        "eye": eye.tolist(), "target": target.tolist(), "up": [0.0, 1.0, 0.0],
        "vfov_deg": VFOV_DEG, "aspect": aspect, "width": WIDTH, "height": HEIGHT,
        "near": dist / 20, "far": dist * 4,
        "sun_direction_to_light": to_sun.tolist(), "sun_irradiance": SUN,
        "world_radiance": WORLD,
        "frame_box": {"min": lo.tolist(), "max": hi.tolist()},
        "glb": os.path.abspath(glb_path),
    }
    if report_path and os.path.isfile(report_path):
        with open(report_path, encoding="utf-8") as f:
            report = json.load(f)
        for name in ("ankle", "knee"):
            p = landmark(report, name)
            if p is not None:
                cam[name] = p
    return cam


def project(cam: dict, points: np.ndarray) -> np.ndarray:
    """Pixel coordinates (x right, y down, pixel centres at +0.5) of world points, as a
    perspective camera with the vertical field of view ``vfov_deg`` draws them (three.js's
    PerspectiveCamera, Blender's camera with sensor_fit VERTICAL)."""
    eye, target, up = (np.array(cam[k], float) for k in ("eye", "target", "up"))
    f = target - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    d = np.atleast_2d(points) - eye
    x, y, z = d @ r, d @ u, d @ f
    t = math.tan(math.radians(cam["vfov_deg"]) / 2)
    ndc_x = x / (z * t * cam["aspect"])
    ndc_y = y / (z * t)
    return np.stack([(ndc_x + 1) / 2 * cam["width"], (1 - ndc_y) / 2 * cam["height"]], axis=1)


# ------------------------------------------------------------------ images

def read_png(path: str) -> np.ndarray:
    """A PNG as float RGB 0-1, H x W x 3 (any alpha dropped)."""
    from PIL import Image
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"), dtype=float) / 255


def luma(img: np.ndarray) -> np.ndarray:
    """Rec. 709 luma of the sRGB-encoded values (0-1): what the eye reads as light/dark."""
    return img @ np.array([0.2126, 0.7152, 0.0722])


def to_linear(img: np.ndarray) -> np.ndarray:
    return np.where(img <= 0.04045, img / 12.92, ((img + 0.055) / 1.055) ** 2.4)


def erode(mask: np.ndarray, r: int) -> np.ndarray:
    """Pixels of `mask` at least `r` pixels (square) from its outside."""
    out = mask.copy()
    for _ in range(r):
        m = out.copy()
        m[1:, :] &= out[:-1, :]
        m[:-1, :] &= out[1:, :]
        m[:, 1:] &= out[:, :-1]
        m[:, :-1] &= out[:, 1:]
        m[0, :] = m[-1, :] = m[:, 0] = m[:, -1] = False
        out = m
    return out


def dilate(mask: np.ndarray, r: int) -> np.ndarray:
    return ~erode(~mask, r)


def local_median(img: np.ndarray, inside: np.ndarray, where: np.ndarray, k: int) -> np.ndarray:
    """Median of `img` over the k x k square around each pixel of `where`, counting only pixels
    `inside` (NaN elsewhere)."""
    r = k // 2
    pad = np.pad(np.where(inside, img, np.nan), r, constant_values=np.nan)
    ys, xs = np.nonzero(where)
    out = np.full(img.shape, np.nan)
    if len(ys):
        win = np.lib.stride_tricks.sliding_window_view(pad, (k, k))[ys, xs].reshape(len(ys), -1)
        out[ys, xs] = np.nanmedian(win, axis=1)
    return out


def iou(a: np.ndarray, b: np.ndarray) -> float:
    u = (a | b).sum()
    return float((a & b).sum() / u) if u else 1.0


# ------------------------------------------------------------------ checks

class Failures:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def check(self, where: str, name: str, ok: bool, why: str) -> bool:
        if not ok:
            self.lines.append(f"FAIL {where} {name}: {why}")
        return ok


def calf_rows(cam: dict, height: int) -> np.ndarray:
    """Rows of the calf: CALF_FROM to CALF_TO of the way from the ankle's centre up to the
    knee's, as the camera projects them (report.json's landmarks, in the file's frame)."""
    rows = np.zeros(height, bool)
    if "ankle" not in cam or "knee" not in cam:
        return rows
    (_, ya), (_, yk) = project(cam, np.array([cam["ankle"], cam["knee"]]))
    lo, hi = sorted((ya + CALF_FROM * (yk - ya), ya + CALF_TO * (yk - ya)))
    rows[max(int(math.ceil(lo)), 0):max(int(math.floor(hi)) + 1, 0)] = True
    return rows


def streaks(img: np.ndarray, leg: np.ndarray, region: np.ndarray,
            smooth_in: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Streak pixels of `region` (bool mask) in the luma image `img`, and its signed local
    contrast.

    A pixel's local contrast is its luma minus the median luma of the STREAK_WINDOW-square around
    it, over leg pixels only (so the background never counts). Smooth shading has none: the median
    of a window over a surface whose luma changes monotonically across it is the centre's value,
    whatever the slope, and a shading extremum is a broad hill or valley that moves a 9-pixel
    median by far less than STREAK_CONTRAST. What a viewer draws wrongly is thin and sharp: depth
    fighting between the stocking and the skin under it (pixels where the skin wins), the leg's
    flat faces poking through the smooth stocking surface (cracks and patches of unveiled skin),
    yarn lines drawn over the surface (speckle). Each departs from its neighbourhood by the
    contrast between skin and stocking or yarn, darker or lighter depending on their colours, so
    both signs count. With `smooth_in` (the bare render's luma) a pixel counts only if that is
    smooth there: the leg's own detail (a skin texture, a low-poly mesh's facets) is not the
    stocking's fault.

    The check runs this on two renders. The dressed one is what a viewer sees on this leg; but
    where skin and stocking are alike in luma a crack is faint there and would show on another
    skin. Over the black leg every pixel where the leg wins the depth test is black against the
    stocking's own shading, so the second figure counts the geometry's faults on any skin."""
    inside = erode(leg, 1)
    contrast = img - local_median(img, inside, region, STREAK_WINDOW)
    hit = region & (np.abs(contrast) > STREAK_CONTRAST)
    if smooth_in is not None:
        hit &= ~(np.abs(smooth_in - local_median(smooth_in, inside, region, STREAK_WINDOW))
                 > STREAK_CONTRAST)
    return hit, contrast


def check_client(case: str, client: str, cam: dict, imgs: dict, fails: Failures) -> dict:
    """Every per-client check on one case; returns the masks the cross-client checks need."""
    where = f"{case}/{client}"
    lum = {k: luma(v) for k, v in imgs.items()}
    lin_y = {k: to_linear(imgs[k]) @ np.array([0.2126, 0.7152, 0.0722])
             for k in ("dressed", "bare", "black_leg")}
    leg = lum["leg"] > 0.5
    stocking = lum["stocking"] > 0.5
    skin = erode(leg, EDGE)
    bare_skin = skin
    uncovered = skin & ~dilate(stocking, EDGE)
    h, _w = leg.shape
    calf = calf_rows(cam, h)[:, None] & skin & erode(stocking, EDGE)
    print(f"  {client}: leg {leg.sum()} px, stocking {stocking.sum()} px, calf {calf.sum()} px "
          f"(rows {np.flatnonzero(calf.any(1))[[0, -1]].tolist() if calf.any() else '-'})")

    # Near-black skin: the bare leg anywhere, the dressed leg where no stocking covers it.
    black_bare = float((lum["bare"][bare_skin] < BLACK_LUMA).mean()) if bare_skin.any() else 0.0
    black_out = float((lum["dressed"][uncovered] < BLACK_LUMA).mean()) if uncovered.any() else 0.0
    print(f"    near-black skin (luma < {BLACK_LUMA}): bare leg {black_bare:.1%} of "
          f"{bare_skin.sum()} px, dressed outside the stocking {black_out:.1%} of "
          f"{uncovered.sum()} px (limit {MAX_BLACK_SHARE:.1%})")
    fails.check(where, "near_black_skin", max(black_bare, black_out) <= MAX_BLACK_SHARE,
                f"{black_bare:.1%} of the bare leg's and {black_out:.1%} of the uncovered "
                f"skin's pixels have luma < {BLACK_LUMA}")
    out = {"leg": leg, "stocking": stocking, "calf": calf}
    if not fails.check(where, "calf", calf.sum() >= 50,
                       f"{calf.sum()} calf pixels (rows between ankle and knee inside both "
                       "silhouettes); wanted at least 50"):
        return out

    worst = 0.0
    for label, img, smooth_in in (("dressed", lum["dressed"], lum["bare"]),
                                  ("over a black leg", lum["black_leg"], None)):
        hit, contrast = streaks(img, leg, calf, smooth_in)
        share = float(hit[calf].mean())
        darker = float((hit & (contrast < 0))[calf].mean())
        worst = max(worst, share)
        print(f"    streaks {label}: {share:.1%} of the calf departs from its "
              f"{STREAK_WINDOW}x{STREAK_WINDOW} median by > {STREAK_CONTRAST} ({darker:.1%} darker, "
              f"{share - darker:.1%} lighter; limit {MAX_STREAK_SHARE:.1%})")
        fails.check(where, f"streaks_{'dressed' if smooth_in is not None else 'black_leg'}",
                    share <= MAX_STREAK_SHARE,
                    f"{share:.1%} of the calf's pixels {label} are streaks ({darker:.1%} darker, "
                    f"{share - darker:.1%} lighter than their neighbourhood)")
    out["streaks"] = hit

    mean_d, mean_b = float(lum["dressed"][calf].mean()), float(lum["bare"][calf].mean())
    # Visible: the colour changes. Not the luma alone: a stocking over a skin of its own luma
    # (today's heat map in Blender) keeps the luma and changes the hue.
    change = float(np.linalg.norm(imgs["dressed"][calf] - imgs["bare"][calf], axis=1).mean())
    # Transmittance: dressed = T * bare + (what the stocking adds), the last being the render
    # over a black leg; in linear light, summed over the calf.
    added = lin_y["dressed"][calf] - lin_y["black_leg"][calf]
    trans = float(added.sum() / max(lin_y["bare"][calf].sum(), 1e-9))
    cols = calf.sum(0) >= max(3, 0.5 * calf.sum(0).max())
    prof_d = np.array([lum["dressed"][calf[:, x], x].mean() for x in np.flatnonzero(cols)])
    prof_b = np.array([lum["bare"][calf[:, x], x].mean() for x in np.flatnonzero(cols)])
    corr = float(np.corrcoef(prof_d, prof_b)[0, 1]) if len(prof_d) > 2 and prof_b.std() > 0 \
        else float("nan")
    print(f"    calf: luma dressed {mean_d:.3f}, bare {mean_b:.3f} ({mean_d - mean_b:+.3f}); "
          f"colour change {change:.3f} (at least {MIN_VISIBLE_DELTA}); transmittance "
          f"{trans:.2f} (wanted {MIN_TRANSMITTANCE}-{MAX_TRANSMITTANCE}); luma profile across "
          f"the leg ({len(prof_d)} columns) correlates {corr:.3f} with the bare leg's "
          f"(at least {MIN_PROFILE_CORR})")
    fails.check(where, "stocking_visible", change >= MIN_VISIBLE_DELTA,
                f"the calf's colour changes by {change:.3f} (mean RGB distance) with the "
                f"stocking, luma {mean_d - mean_b:+.3f}")
    fails.check(where, "stocking_see_through",
                MIN_TRANSMITTANCE <= trans <= MAX_TRANSMITTANCE and corr >= MIN_PROFILE_CORR,
                f"transmittance {trans:.2f}, profile correlation {corr:.3f}")
    # "Stocking over skin": where the stocking changes the picture (3x3 mean, so render noise
    # and single yarn pixels do not decide it).
    diff = np.abs(lum["dressed"] - lum["bare"])
    pad = np.pad(diff, 1, mode="edge")
    smooth = sum(pad[dy:dy + diff.shape[0], dx:dx + diff.shape[1]]
                 for dy in range(3) for dx in range(3)) / 9
    out["covered"] = skin & (smooth > COVERED_DELTA)
    return out


def check_case(case_dir: str) -> list[str]:
    """All checks of one case (one fit); returns the failure lines."""
    case = os.path.basename(os.path.normpath(case_dir))
    fails = Failures()
    with open(os.path.join(case_dir, "camera.json"), encoding="utf-8") as f:
        cam = json.load(f)
    print(f"{case}: {cam['glb']}")
    results = {}
    for client in CLIENTS:
        paths = {r: os.path.join(case_dir, client, f"{r}.png") for r in RENDERS}
        absent = [p for p in paths.values() if not os.path.isfile(p)]
        if not fails.check(f"{case}/{client}", "renders", not absent,
                           f"missing {', '.join(absent)}"):
            continue
        imgs = {r: read_png(p) for r, p in paths.items()}
        shape = (cam["height"], cam["width"], 3)
        if not fails.check(f"{case}/{client}", "size",
                           all(i.shape == shape for i in imgs.values()),
                           f"sizes {[i.shape for i in imgs.values()]}, wanted {shape}"):
            continue
        results[client] = check_client(case, client, cam, imgs, fails)
    if len(results) == 2:
        a, b = (results[c] for c in CLIENTS)
        leg_iou = iou(a["leg"], b["leg"])
        cov_iou = iou(a["covered"], b["covered"])
        print(f"  agreement: leg silhouettes IoU {leg_iou:.3f} (wanted {MIN_LEG_IOU}); "
              f"'stocking over skin' ({a['covered'].sum()} / {b['covered'].sum()} px) IoU "
              f"{cov_iou:.3f} (wanted {MIN_COVERED_IOU})")
        fails.check(case, "leg_silhouettes_agree", leg_iou >= MIN_LEG_IOU,
                    f"IoU {leg_iou:.3f} of the two clients' leg silhouettes")
        fails.check(case, "stocking_regions_agree", cov_iou >= MIN_COVERED_IOU,
                    f"IoU {cov_iou:.3f} of where each client shows stocking over skin")
    return fails.lines


def main(argv: list[str]) -> int:
    if len(argv) == 3 and argv[0] == "camera":
        fit_dir, out = argv[1], argv[2]
        cam = make_camera(os.path.join(fit_dir, "stocking.glb"),
                          os.path.join(fit_dir, "report.json"))
        os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
        with open(out, "w", encoding="utf-8") as f:
            json.dump(cam, f, indent=1)
        return 0
    if len(argv) >= 2 and argv[0] == "check":
        lines = []
        for case_dir in argv[1:]:
            lines += check_case(case_dir)
        for line in lines:
            print(line)
        print(f"client pixel checks: {len(lines)} failed" if lines else "client pixel checks: all passed")
        return 1 if lines else 0
    print("\n\n".join(__doc__.split("\n\n")[1:3]), file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
