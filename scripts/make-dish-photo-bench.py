#!/usr/bin/env python3
"""The independent dish photo benchmark (issue 16): photo-realistic renders of dishes that
procfit did not make, by a physically based renderer procfit did not write (Mitsuba 3).

Every dish is written here as a lathed profile from measured dimensions of real tableware (a
300 ml mug, a teacup, an espresso cup, a cappuccino cup, bowls, a tumbler, a vase) plus a swept
handle where it has one; saucers and spoons are separate meshes. Each case is a scene on a
wooden table (a procedural plank texture made here), in front of a plaster wall, lit by a
ceiling area light and an environment with a bright window (soft shadows, glossy reflections
in the glaze: Mitsuba's `plastic`/`roughplastic`, a dielectric coat over a diffuse base), seen
from 10°-60° above the table through a 35-70 mm (35 mm-equivalent) lens.

Per case, in `OUT/NAME/`:
  photo.png      the photo (sRGB)
  mask.png       the true object mask: the object's visible pixels (white), everything else
                 black; a spoon in front of the object hides it (an AOV pass, box filter, so the
                 edge pixels are coverage)
  mask_full.png  the object's whole silhouette (the object alone in the scene): what a fitted
                 model should cover
  truth.obj      the object's true mesh in the scene's frame (metres, Y up, table at y = 0),
                 one `o` per part: the dish, and its saucer when it stands on one
  spoon.obj      the spoon, when there is one (never part of the object)
  camera.json    name, kind, width, height, fov_y (radians, vertical), focal_35mm, position,
                 target, up, elevation_deg, object_parts, has_saucer, spoon, seed

What is "the object": the dish, with its saucer when it stands on one (procfit's dish generator
has a saucer part); a spoon never is.

Usage: python3 scripts/make-dish-photo-bench.py [--out target/dish-photo-bench] [--spp 96]
       [--threads 1] [NAME ...]
Needs `pip install mitsuba` (the scalar_rgb variant needs nothing else). Every random choice
(shapes, placement, camera, textures, lights) comes from the case's seed and Mitsuba's sampler
is seeded: the meshes, cameras and masks are byte-identical run to run. The photo's Monte Carlo
noise is not under the LLVM variant (two runs of bowl-30 differ by 2 levels of 255 on average,
35 at most), so a bench figure can move a little after the photos are made again.
"""

import argparse
import json
import math
import os
import sys

import numpy as np

# ---------------------------------------------------------------------------------------------
# Meshes


class MeshBuilder:
    """An indexed triangle mesh, counter-clockwise outward triangles."""

    def __init__(self):
        self.v = []
        self.f = []

    def add_vertex(self, p):
        self.v.append(tuple(float(x) for x in p))
        return len(self.v) - 1

    def arrays(self):
        return np.array(self.v, dtype=np.float64), np.array(self.f, dtype=np.int64)


def lathe(profile_mm, sectors=64):
    """A closed surface of revolution about +Y from a profile of (radius, height) in mm, from
    the bottom centre over the outside and the rim down the inside back to the axis (as the
    measured mug of procfit's tests); points on the axis become one vertex (a fan)."""
    m = MeshBuilder()
    rings = []
    for r, y in profile_mm:
        if r <= 1e-9:
            rings.append([m.add_vertex((0.0, y * 1e-3, 0.0))] * sectors)
        else:
            ring = []
            for s in range(sectors):
                a = 2 * math.pi * s / sectors
                ring.append(m.add_vertex((r * math.cos(a) * 1e-3, y * 1e-3, -r * math.sin(a) * 1e-3)))
            rings.append(ring)
    for k in range(len(rings) - 1):
        for s in range(sectors):
            a, b = rings[k][s], rings[k][(s + 1) % sectors]
            c, d = rings[k + 1][s], rings[k + 1][(s + 1) % sectors]
            for t in ((a, b, d), (a, d, c)):
                if len(set(t)) == 3:
                    m.f.append(t)
    return m.arrays()


def radius_at(profile_mm, y):
    """The outside radius of a lathe profile at height y (mm): the largest radius of the
    profile's segments crossing y."""
    best = 0.0
    for (r0, y0), (r1, y1) in zip(profile_mm, profile_mm[1:]):
        if min(y0, y1) <= y <= max(y0, y1) and y1 != y0:
            best = max(best, r0 + (r1 - r0) * (y - y0) / (y1 - y0))
    return best


def sweep(path_mm, half_w, half_t, ring=14):
    """A tube swept along a path of (x, y) centre points in the z = 0 plane (mm), with an
    elliptic cross-section: half-width `half_w` in the path's plane, half-thickness `half_t`
    across it; both ends capped."""
    m = MeshBuilder()
    pts = np.array(path_mm, dtype=np.float64)
    n = len(pts)
    rings = []
    for i in range(n):
        t = pts[min(i + 1, n - 1)] - pts[max(i - 1, 0)]
        t /= np.linalg.norm(t)
        nrm = np.array([-t[1], t[0]])
        section = []
        for j in range(ring):
            u = 2 * math.pi * j / ring
            off = half_w * math.cos(u) * nrm
            section.append(m.add_vertex(((pts[i][0] + off[0]) * 1e-3, (pts[i][1] + off[1]) * 1e-3,
                                         half_t * math.sin(u) * 1e-3)))
        rings.append(section)
    for i in range(n - 1):
        for j in range(ring):
            a, b = rings[i][j], rings[i][(j + 1) % ring]
            c, d = rings[i + 1][j], rings[i + 1][(j + 1) % ring]
            m.f.append((a, d, b))
            m.f.append((a, c, d))
    # Caps: a fan around each end's centre.
    for i, flip in ((0, False), (n - 1, True)):
        c = m.add_vertex((pts[i][0] * 1e-3, pts[i][1] * 1e-3, 0.0))
        for j in range(ring):
            a, b = rings[i][j], rings[i][(j + 1) % ring]
            m.f.append((c, a, b) if flip else (c, b, a))
    v, f = m.arrays()
    # Orient outward: flip every triangle when the signed volume is negative.
    if signed_volume(v, f) < 0:
        f = f[:, ::-1]
    return v, f


def signed_volume(v, f):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def handle_path(profile_mm, y_top, y_bottom, reach, shape, steps=28):
    """The centre line of a handle on the +X side from the body at `y_top` to the body at
    `y_bottom` (mm), reaching `reach` mm beyond the body: `round` a half circle-like loop (a
    mug), `ear` a loop fuller at the top (a teacup), each end 1.5 mm inside the wall."""
    x_top = radius_at(profile_mm, y_top) - 1.5
    x_bot = radius_at(profile_mm, y_bottom) - 1.5
    pts = []
    for i in range(steps + 1):
        s = i / steps
        t = math.pi * s  # 0 at the top, π at the bottom
        y = y_top + (y_bottom - y_top) * (0.5 - 0.5 * math.cos(t))
        if shape == "ear":
            # The widest point a third of the way down, as on a teacup's handle.
            bulge = math.sin(math.pi * s ** 0.75)
            y = y_top + (y_bottom - y_top) * (s ** 1.15)
        else:
            bulge = math.sin(t)
        base = x_top + (x_bot - x_top) * s
        pts.append((base + reach * bulge, y))
    return pts


def merge(*meshes):
    vs, fs, off = [], [], 0
    for v, f in meshes:
        vs.append(v)
        fs.append(f + off)
        off += len(v)
    return np.concatenate(vs), np.concatenate(fs)


def transform(v, yaw=0.0, translate=(0.0, 0.0, 0.0)):
    c, s = math.cos(yaw), math.sin(yaw)
    r = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return v @ r.T + np.array(translate)


def spoon_mesh(length_mm=130.0):
    """A teaspoon lying along +X from the bowl's far end at x = 0: an ellipsoidal bowl (40 ×
    26 × 7 mm, flattened) and a flat tapering handle, slightly curved up at its end."""
    m_bowl = MeshBuilder()
    nu, nv = 24, 12
    a, b, c = 20.0, 13.0, 3.5
    idx = {}
    for i in range(nv + 1):
        th = math.pi * i / nv
        for j in range(nu):
            ph = 2 * math.pi * j / nu
            if i in (0, nv):
                key = (i, 0)
                if key not in idx:
                    idx[key] = m_bowl.add_vertex(((a) * 1e-3, (c * math.cos(th)) * 1e-3, 0.0))
                idx[(i, j)] = idx[key]
                continue
            x = a + a * math.sin(th) * math.cos(ph)
            z = b * math.sin(th) * math.sin(ph)
            y = c * math.cos(th)
            idx[(i, j)] = m_bowl.add_vertex((x * 1e-3, y * 1e-3, z * 1e-3))
    for i in range(nv):
        for j in range(nu):
            p, q = idx[(i, j)], idx[(i, (j + 1) % nu)]
            r, s = idx[(i + 1, j)], idx[(i + 1, (j + 1) % nu)]
            for t in ((p, r, s), (p, s, q)):
                if len(set(t)) == 3:
                    m_bowl.f.append(t)
    bowl = m_bowl.arrays()
    if signed_volume(*bowl) < 0:
        bowl = (bowl[0], bowl[1][:, ::-1])
    # The handle: a flat bar from inside the bowl's end to the tip, widening towards the tip.
    n = 20
    x0, x1 = 2 * a - 4.0, length_mm
    path, widths = [], []
    for i in range(n + 1):
        s = i / n
        x = x0 + (x1 - x0) * s
        y = 2.0 + 6.0 * s * s
        path.append((x, y))
        widths.append(2.5 + 3.0 * s * s)
    hv, hf = sweep(path, 1.0, 1.0, ring=10)
    # Scale each ring's z (across the bar) by its width: rings are consecutive blocks of 10.
    hv = hv.copy()
    for i in range(n + 1):
        hv[i * 10:(i + 1) * 10, 2] *= widths[i]
    hv[-2:, 2] = 0.0
    return merge(bowl, (hv, hf))


def orient_along(v, start, end):
    """Moves a mesh lying along +X from the origin so it runs from `start` towards `end`."""
    d = np.array(end, dtype=np.float64) - np.array(start, dtype=np.float64)
    d /= np.linalg.norm(d)
    # Rotation taking +X to d, keeping the mesh's +Y as close to world +Y as possible.
    side = np.cross(d, [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    up = np.cross(side, d)
    r = np.stack([d, up, -side], axis=1)
    return v @ r.T + np.array(start)


# ---------------------------------------------------------------------------------------------
# Measured dishes (mm). Profiles go from the bottom centre over the outside and the rim down the
# inside to the inner bottom's centre.

MUG = [(0, 0), (36, 0), (39, 1.5), (40, 5), (40, 60), (40, 95), (38, 95), (36, 93), (36, 10), (33, 6), (0, 6)]
# A porcelain teacup, 200 ml: rim Ø 92, 62 high, foot ring Ø 46 × 6.
TEACUP = [(0, 4), (20, 4), (21, 0), (24, 0), (25, 6), (33, 14), (40, 26), (44, 42), (46, 58), (46.5, 62),
          (44.5, 62), (43.5, 57), (41, 40), (36, 25), (27, 12), (18, 8), (0, 8)]
# A thick espresso cup, 80 ml: rim Ø 62, 57 high, foot Ø 36, 5 mm walls.
ESPRESSO = [(0, 0), (17, 0), (18, 2), (22, 8), (27, 18), (30, 32), (31, 48), (31, 57), (27, 57), (26, 50),
            (25.5, 33), (22, 20), (16, 12), (0, 11)]
# A cappuccino cup, 180 ml: rim Ø 90, 66 high, rounded, foot Ø 48.
CAPPUCCINO = [(0, 3), (22, 3), (24, 0), (27, 0), (29, 5), (37, 14), (43, 28), (45, 45), (45, 66), (42, 66),
              (41.5, 47), (39.5, 30), (34, 17), (24, 10), (0, 9)]
# A cereal bowl: rim Ø 150, 65 high, foot ring Ø 62.
BOWL = [(0, 3), (28, 3), (30, 0), (33, 0), (34, 5), (48, 14), (62, 29), (71, 46), (75, 61), (75, 65), (71, 65),
        (70, 59), (66, 44), (57, 28), (44, 16), (30, 10), (0, 9)]
# A wide serving bowl: rim Ø 200, 80 high, foot ring Ø 90.
SERVING_BOWL = [(0, 4), (42, 4), (44, 0), (48, 0), (50, 6), (70, 18), (86, 38), (96, 60), (100, 78), (100, 80),
                (95, 80), (94, 74), (90, 57), (81, 37), (66, 22), (46, 13), (0, 12)]
# A stoneware tumbler: Ø 72 at the rim, 64 at the foot, 100 high.
TUMBLER = [(0, 0), (30, 0), (32, 2), (36, 70), (36, 100), (32.5, 100), (32.5, 70), (28.5, 8), (0, 8)]
# A bud vase: Ø 110 belly, Ø 40 neck, Ø 52 lip, 190 high.
VASE = [(0, 0), (35, 0), (38, 3), (50, 30), (55, 60), (52, 90), (40, 120), (23, 145), (19, 165), (22, 182),
        (26, 188), (26, 190), (22, 190), (16, 183), (15, 165), (18, 145), (34, 120), (47, 90), (50, 60),
        (45, 30), (32, 8), (0, 8)]
# Saucers: foot ring, underside, rim lip, top, well.
SAUCER_140 = [(0, 0), (32, 0), (36, 2), (66, 12), (70, 15), (69.5, 17), (65, 16), (30, 5), (0, 5)]
SAUCER_115 = [(0, 0), (26, 0), (29, 2), (54, 11), (57.5, 14), (57, 15.5), (53, 14.5), (24, 5), (0, 5)]
SAUCER_150 = [(0, 0), (30, 0), (35, 2), (72, 13), (75, 15), (74, 16), (70, 16), (38, 4), (0, 4)]

DISHES = {
    "mug": dict(profile=MUG, handle=dict(y_top=82, y_bottom=20, reach=26, shape="round", w=5.0, t=5.0)),
    "teacup": dict(profile=TEACUP, handle=dict(y_top=54, y_bottom=22, reach=20, shape="ear", w=3.2, t=4.0)),
    "espresso": dict(profile=ESPRESSO, handle=dict(y_top=48, y_bottom=24, reach=15, shape="ear", w=3.5, t=4.0)),
    "cappuccino": dict(profile=CAPPUCCINO, handle=dict(y_top=56, y_bottom=26, reach=19, shape="ear", w=3.5, t=4.5)),
    "bowl": dict(profile=BOWL, handle=None),
    "serving-bowl": dict(profile=SERVING_BOWL, handle=None),
    "tumbler": dict(profile=TUMBLER, handle=None),
    "vase": dict(profile=VASE, handle=None),
}
SAUCERS = {"140": (SAUCER_140, 5.0), "115": (SAUCER_115, 5.0), "150": (SAUCER_150, 4.0)}


def dish_mesh(kind):
    d = DISHES[kind]
    body = lathe(d["profile"])
    if d["handle"] is None:
        return body
    h = d["handle"]
    path = handle_path(d["profile"], h["y_top"], h["y_bottom"], h["reach"], h["shape"])
    return merge(body, sweep(path, h["w"], h["t"]))


# ---------------------------------------------------------------------------------------------
# The cases: dish, saucer, spoon, glaze, camera elevation (degrees), lens (35 mm-equivalent),
# image size, the dish's yaw (degrees; 0 puts the handle on +X) and the camera's azimuth.

CASES = [
    dict(name="mug-side", kind="mug", saucer=None, spoon=None, glaze=(0.85, 0.85, 0.82), rough=0.0,
         elev=15, focal=50, size=(512, 384), yaw=0, azim=0, seed=1),
    dict(name="mug-spoon-45", kind="mug", saucer=None, spoon="in", glaze=(0.12, 0.25, 0.55), rough=0.06,
         elev=45, focal=35, size=(512, 384), yaw=-30, azim=0, seed=2),
    dict(name="mug-above-60", kind="mug", saucer=None, spoon=None, glaze=(0.75, 0.18, 0.12), rough=0.0,
         elev=60, focal=50, size=(512, 384), yaw=35, azim=0, seed=3),
    dict(name="teacup-saucer-35", kind="teacup", saucer="140", spoon=None, glaze=(0.9, 0.9, 0.88), rough=0.0,
         elev=35, focal=50, size=(512, 384), yaw=10, azim=0, seed=4),
    dict(name="teacup-50", kind="teacup", saucer=None, spoon=None, glaze=(0.35, 0.55, 0.45), rough=0.04,
         elev=50, focal=70, size=(512, 384), yaw=-15, azim=0, seed=5),
    dict(name="espresso-saucer-spoon-45", kind="espresso", saucer="115", spoon="in", glaze=(0.92, 0.92, 0.9),
         rough=0.0, elev=45, focal=50, size=(512, 384), yaw=20, azim=0, seed=6),
    dict(name="espresso-10", kind="espresso", saucer=None, spoon=None, glaze=(0.1, 0.1, 0.11), rough=0.05,
         elev=10, focal=70, size=(512, 384), yaw=0, azim=0, seed=7),
    dict(name="cappuccino-saucer-spoon-25", kind="cappuccino", saucer="150", spoon="beside",
         glaze=(0.8, 0.55, 0.2), rough=0.03, elev=25, focal=35, size=(512, 384), yaw=-10, azim=0, seed=8),
    dict(name="bowl-30", kind="bowl", saucer=None, spoon=None, glaze=(0.88, 0.86, 0.8), rough=0.0,
         elev=30, focal=50, size=(512, 384), yaw=0, azim=0, seed=9),
    dict(name="serving-bowl-55", kind="serving-bowl", saucer=None, spoon=None, glaze=(0.2, 0.35, 0.6), rough=0.08,
         elev=55, focal=35, size=(512, 384), yaw=0, azim=0, seed=10),
    dict(name="tumbler-20", kind="tumbler", saucer=None, spoon=None, glaze=(0.5, 0.42, 0.35), rough=0.15,
         elev=20, focal=50, size=(384, 512), yaw=0, azim=0, seed=11),
    dict(name="vase-12", kind="vase", saucer=None, spoon=None, glaze=(0.3, 0.5, 0.42), rough=0.02,
         elev=12, focal=70, size=(384, 512), yaw=0, azim=0, seed=12),
]

# ---------------------------------------------------------------------------------------------
# Textures


def value_noise(shape, cells, rng):
    """Smooth value noise over an image of `shape`, `cells` lattice cells across (per axis)."""
    h, w = shape
    cy, cx = cells
    grid = rng.random((cy + 2, cx + 2))
    ys = np.linspace(0, cy, h, endpoint=False)
    xs = np.linspace(0, cx, w, endpoint=False)
    y0, x0 = ys.astype(int), xs.astype(int)
    fy, fx = ys - y0, xs - x0
    fy, fx = fy * fy * (3 - 2 * fy), fx * fx * (3 - 2 * fx)
    g00 = grid[y0][:, x0]
    g01 = grid[y0][:, x0 + 1]
    g10 = grid[y0 + 1][:, x0]
    g11 = grid[y0 + 1][:, x0 + 1]
    top = g00 + (g01 - g00) * fx[None, :]
    bot = g10 + (g11 - g10) * fx[None, :]
    return top + (bot - top) * fy[:, None]


def wood_texture(rng, side=2048, planks=12):
    """A plank table top (linear RGB, side × side): along-the-grain rings and streaks, a tint
    per plank, dark joints between planks."""
    u = np.linspace(0, 1, side, endpoint=False)
    plank = np.floor(u * planks).astype(int)
    within = u * planks - plank
    img = np.zeros((side, side, 3))
    # Grain runs along rows (the texture's x); rings vary across (y) and slowly along.
    warp = value_noise((side, side), (6, 4), rng) * 4.0 + value_noise((side, side), (50, 16), rng) * 0.6
    streak = value_noise((side, side), (600, 6), rng)
    tint = rng.random(planks)
    offset = rng.random(planks) * 5
    rings_per_plank = 2 + 3 * rng.random(planks)
    ring_phase = within[:, None] * rings_per_plank[plank][:, None] + offset[plank][:, None] + warp
    ring = np.abs(np.sin(math.pi * ring_phase)) ** 3
    light = np.array([0.42, 0.24, 0.11])
    dark = np.array([0.20, 0.10, 0.04])
    t = np.clip(0.4 * ring + 0.5 * streak + 0.3 * tint[plank][:, None] - 0.1, 0, 1)
    img = light[None, None, :] * (1 - t[..., None]) + dark[None, None, :] * t[..., None]
    joint = (within < 0.006) | (within > 0.994)
    img[joint] *= 0.25
    return img.astype(np.float32)


def plaster_texture(rng, side=512):
    n = value_noise((side, side), (30, 30), rng) * 0.6 + value_noise((side, side), (120, 120), rng) * 0.4
    base = np.array([0.62, 0.58, 0.52])
    img = base[None, None, :] * (0.9 + 0.12 * n[..., None])
    return img.astype(np.float32)


def environment(rng, w=512, h=256):
    """A lat-long room: dim warm walls, a brighter ceiling, a bright window on one side."""
    th = (np.arange(h) + 0.5) / h * math.pi  # 0 at +Y
    ph = (np.arange(w) + 0.5) / w * 2 * math.pi
    img = np.zeros((h, w, 3))
    up = np.cos(th)[:, None] * np.ones((1, w))
    img += np.array([0.45, 0.42, 0.36]) * (0.6 + 0.4 * np.clip(up, 0, 1))[..., None]
    win_c = rng.random() * 2 * math.pi
    dphi = np.angle(np.exp(1j * (ph - win_c)))
    win = (np.abs(dphi)[None, :] < 0.45) & (th[:, None] > 0.55) & (th[:, None] < 1.35)
    img[win] = np.array([3.2, 3.4, 3.8])
    return img.astype(np.float32)


# ---------------------------------------------------------------------------------------------
# Scenes


def fov_from_focal(focal, width, height):
    """Vertical field of view of a 35 mm-equivalent focal length (the 43.27 mm diagonal), as
    procfit reads EXIF (`fov_from_focal_35mm`)."""
    half_diag = 0.5 * math.hypot(36.0, 24.0)
    return 2.0 * math.atan(half_diag / focal * height / math.hypot(width, height))


def build_case(case):
    """The object's meshes (name, v, f), the spoon's (or None) and the camera."""
    rng = np.random.default_rng(case["seed"])
    yaw = math.radians(case["yaw"])
    parts = []
    lift = 0.0
    if case["saucer"]:
        prof, well = SAUCERS[case["saucer"]]
        parts.append(("saucer", *lathe(prof)))
        lift = well * 1e-3
    dv, df = dish_mesh(case["kind"])
    dv = transform(dv, yaw, (0.0, lift, 0.0))
    parts.insert(0, ("dish", dv, df))
    spoon = None
    prof = DISHES[case["kind"]]["profile"]
    rim_y = max(y for _, y in prof)
    rim_r = radius_at(prof, rim_y - 0.01)
    inner_bottom = min(y for r, y in prof if r == 0 and y > 0) if any(r == 0 and y > 0 for r, y in prof) else 6.0
    if case["spoon"] == "in":
        # The bowl rests on the inner bottom on the near side, the handle leans on the far rim
        # (seen from the camera on +Z) and sticks out over it, as one leaves a spoon in a cup.
        phi = math.radians(75 + 30 * rng.random())
        d = np.array([math.cos(phi), 0.0, -math.sin(phi)])
        start = -d * (rim_r - 14) * 1e-3 + np.array([0, (inner_bottom + 4) * 1e-3 + lift, 0])
        contact = d * (rim_r + 1) * 1e-3 + np.array([0, (rim_y + 3) * 1e-3 + lift, 0])
        sv, sf = spoon_mesh(120.0 if case["kind"] != "espresso" else 100.0)
        spoon = (orient_along(sv, start, contact), sf)
    elif case["spoon"] == "beside":
        # On the table in front of the saucer, turned a little.
        sv, sf = spoon_mesh(125.0)
        sr = SAUCERS[case["saucer"]][0][4][0] if case["saucer"] else rim_r
        start = np.array([-0.06, 0.0035, (sr + 18) * 1e-3])
        end = start + np.array([1.0, 0.0, 0.25])
        spoon = (orient_along(sv, start, end), sf)
    # The camera: at the case's elevation, the bounding sphere 70-85 % of the image's short side.
    w, h = case["size"]
    fov_y = fov_from_focal(case["focal"], w, h)
    allv = np.concatenate([p[1] for p in parts])
    lo, hi = allv.min(0), allv.max(0)
    centre = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo))
    fill = 0.7 + 0.15 * rng.random()
    dist = radius / math.tan(0.5 * fov_y * fill) if h <= w else radius / math.tan(0.5 * fov_from_focal(case["focal"], h, w) * fill)
    el, az = math.radians(case["elev"]), math.radians(case["azim"])
    eye = centre + dist * np.array([math.sin(az) * math.cos(el), math.sin(el), math.cos(az) * math.cos(el)])
    target = centre + radius * 0.08 * (rng.random(3) - 0.5) * np.array([1, 0.5, 1])
    cam = dict(
        name=case["name"], kind=case["kind"], width=w, height=h, fov_y=fov_y, focal_35mm=case["focal"],
        position=eye.tolist(), target=target.tolist(), up=[0.0, 1.0, 0.0], elevation_deg=case["elev"],
        object_parts=[p[0] for p in parts], has_saucer=case["saucer"] is not None,
        spoon=case["spoon"] or "none", seed=case["seed"],
    )
    return parts, spoon, cam


def write_obj(path, parts):
    with open(path, "w") as out:
        out.write("# procfit dish photo benchmark truth (metres, Y up)\n")
        base = 1
        for name, v, f in parts:
            out.write(f"o {name}\n")
            for p in v:
                out.write(f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}\n")
            for t in f:
                out.write(f"f {t[0] + base} {t[1] + base} {t[2] + base}\n")
            base += len(v)


def render_case(mi, dr, case, out_dir, spp):
    parts, spoon, cam = build_case(case)
    os.makedirs(out_dir, exist_ok=True)
    write_obj(os.path.join(out_dir, "truth.obj"), parts)
    if spoon is not None:
        write_obj(os.path.join(out_dir, "spoon.obj"), [("spoon", *spoon)])
    # Mitsuba reads the meshes from OBJ files (one per shape) written beside the case.
    mesh_dir = os.path.join(out_dir, "meshes")
    os.makedirs(mesh_dir, exist_ok=True)
    shapes = {}
    for name, v, f in parts:
        p = os.path.join(mesh_dir, f"{name}.obj")
        write_obj(p, [(name, v, f)])
        shapes[name] = p
    if spoon is not None:
        shapes["spoon"] = os.path.join(out_dir, "spoon.obj")
    rng = np.random.default_rng(1000 + case["seed"])
    wood = wood_texture(rng)
    plaster = plaster_texture(rng)
    env = environment(rng)
    w, h = cam["width"], cam["height"]
    sensor = {
        "type": "perspective",
        "fov": math.degrees(cam["fov_y"]),
        "fov_axis": "y",
        "near_clip": 0.005,
        "to_world": mi.ScalarTransform4f().look_at(origin=cam["position"], target=cam["target"], up=[0, 1, 0]),
        "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "gaussian"}},
        "sampler": {"type": "independent", "sample_count": spp, "seed": case["seed"]},
    }
    glaze = {
        "type": "plastic" if case["rough"] == 0 else "roughplastic",
        "diffuse_reflectance": {"type": "rgb", "value": list(case["glaze"])},
        "int_ior": 1.5,
    }
    if case["rough"] > 0:
        glaze["alpha"] = case["rough"]
        glaze["distribution"] = "ggx"
    white = {"type": "plastic", "diffuse_reflectance": {"type": "rgb", "value": [0.88, 0.88, 0.86]}, "int_ior": 1.5}
    # A table 1.6 m square, its planks along X, and a wall 0.9 m behind the object (seen from
    # the camera) with the table's far edge 0.6 m behind it.
    az = math.radians(case["azim"])
    back = np.array([-math.sin(az), 0.0, -math.cos(az)])
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 8},
        "sensor": sensor,
        "env": {"type": "envmap", "bitmap": mi.Bitmap(env), "scale": 1.0},
        "lamp": {
            "type": "rectangle",
            "to_world": mi.ScalarTransform4f().look_at(origin=[0.35, 1.1, 0.25], target=[0, 0, 0], up=[0, 1, 0])
            @ mi.ScalarTransform4f().scale([0.25, 0.25, 1]),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [10.0, 9.3, 8.2]}},
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}},
        },
        "table": {
            "type": "rectangle",
            "to_world": mi.ScalarTransform4f().translate(list(back * 0.2))
            @ mi.ScalarTransform4f().rotate([1, 0, 0], -90)
            @ mi.ScalarTransform4f().rotate([0, 0, 1], float(rng.random() * 360))
            @ mi.ScalarTransform4f().scale([0.8, 0.8, 1]),
            "bsdf": {
                "type": "roughplastic",
                "distribution": "ggx",
                "alpha": 0.25,
                "int_ior": 1.5,
                "diffuse_reflectance": {"type": "bitmap", "bitmap": mi.Bitmap(wood), "raw": True},
            },
        },
        "wall": {
            "type": "rectangle",
            "to_world": mi.ScalarTransform4f().look_at(origin=list(back * 1.0 + np.array([0, 0.6, 0])),
                                                       target=[0, 0.6, 0], up=[0, 1, 0])
            @ mi.ScalarTransform4f().scale([1.5, 0.9, 1]),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "bitmap", "bitmap": mi.Bitmap(plaster), "raw": True}},
        },
    }
    for name, path in shapes.items():
        if name == "spoon":
            bsdf = {"type": "roughconductor", "material": "Al", "alpha": 0.2}
        elif name == "saucer":
            bsdf = glaze if case["kind"] in ("espresso",) else white
            if case["kind"] == "cappuccino":
                bsdf = glaze
        else:
            bsdf = glaze
        scene[name] = {"type": "obj", "filename": path, "face_normals": False, "bsdf": bsdf}
    img = np.array(mi.render(mi.load_dict(scene), spp=spp))[..., :3]
    # Exposure and a gentle shoulder, then sRGB: a camera's JPEG-like look.
    x = np.clip(img * 1.3, 0, None)
    x = x / (1 + 0.15 * x)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.clip(x, 1e-8, None), 1 / 2.4) - 0.055)
    write_png(os.path.join(out_dir, "photo.png"), np.clip(srgb * 255 + 0.5, 0, 255).astype(np.uint8))
    # The masks: an AOV pass of the albedo, the object white and everything else black.
    for fname, with_others in (("mask.png", True), ("mask_full.png", False)):
        mscene = {
            "type": "scene",
            "integrator": {"type": "aov", "aovs": "a:albedo"},
            "sensor": dict(sensor, film={"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"}},
                           sampler={"type": "independent", "sample_count": 64, "seed": case["seed"]}),
        }
        for name, path in shapes.items():
            is_object = name != "spoon"
            if not is_object and not with_others:
                continue
            value = 1.0 if is_object else 0.0
            mscene[name] = {"type": "obj", "filename": path, "face_normals": True,
                            "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [value] * 3}}}}
        if with_others:
            mscene["table"] = dict(scene["table"], bsdf={"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}})
        a = np.array(mi.render(mi.load_dict(mscene), spp=64))
        cov = a[..., -1] if a.shape[-1] > 3 else a[..., 0]
        write_png(os.path.join(out_dir, fname), np.clip(cov * 255 + 0.5, 0, 255).astype(np.uint8))
    with open(os.path.join(out_dir, "camera.json"), "w") as out:
        json.dump(cam, out, indent=2)
        out.write("\n")
    return cam


def write_png(path, arr):
    import zlib
    import struct

    arr = np.ascontiguousarray(arr)
    h, w = arr.shape[:2]
    channels = 1 if arr.ndim == 2 else arr.shape[2]
    color_type = {1: 0, 3: 2, 4: 6}[channels]
    raw = b"".join(b"\x00" + arr[y].tobytes() for y in range(h))

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, color_type, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as out:
        out.write(png)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "target", "dish-photo-bench"))
    ap.add_argument("--spp", type=int, default=96, help="samples per pixel of the photo")
    ap.add_argument("--threads", type=int, default=1, help="render threads")
    ap.add_argument("--variant", default=None,
                    help="Mitsuba variant: llvm_ad_rgb (about 4x faster; needs Debian's libllvm19) when "
                    "libLLVM 19 is found, else scalar_rgb (needs nothing)")
    ap.add_argument("names", nargs="*")
    a = ap.parse_args()
    llvm19 = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
    if a.variant is None:
        a.variant = "llvm_ad_rgb" if os.path.exists(llvm19) else "scalar_rgb"
    # Dr.Jit takes the first libLLVM it finds; an older one (15) crashes in its code generator.
    if a.variant.startswith("llvm") and "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(llvm19):
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm19
    try:
        import drjit as dr
        import mitsuba as mi
    except ImportError:
        sys.exit("make-dish-photo-bench: needs Mitsuba 3: pip install mitsuba")
    mi.set_variant(a.variant)
    print(f"Mitsuba {mi.__version__}, variant {a.variant}, {a.spp} spp, {a.threads} thread(s)", flush=True)
    dr.set_thread_count(a.threads)
    for case in CASES:
        if a.names and case["name"] not in a.names:
            continue
        out_dir = os.path.join(a.out, case["name"])
        cam = render_case(mi, dr, case, out_dir, a.spp)
        print(f"{case['name']}: {cam['width']}x{cam['height']}, {case['elev']}° above, {case['focal']} mm "
              f"-> {os.path.normpath(out_dir)}", flush=True)


if __name__ == "__main__":
    main()
