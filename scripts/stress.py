#!/usr/bin/env python3
"""Writes synthetic work-cell photos the development split does not have, in its layout.

Backgrounds from white to black and saturated card, cables of every colour (black and
white among them) that cross, run out of the frame at both ends, or end in view with a
metal terminal; shaded (a darker rim, a lighter core), 7-11 px wide at 640x480, smooth
(bends no tighter than about 40 px); and two kinds on any of those backgrounds: thin
rods 3-5 px wide with blunt ends (`thin`), pairs of same-colour cables lying side by
side, 0-4 px apart (`pairs`), cables that loop over themselves once (`loops`, a loop
30-70 px in radius), and one or two power cables 14-22 px wide among 2-4 wires 5-8 px
wide (`mixed`); cables casting soft shadows on textured surfaces (`textured`: a
cutting mat's grid, perforated metal, cork or granite, planks, twill, tiles); and
crowded tables (`crowded`: 6-10 cables, as many as the development photos hold, 4-10
with a median of 7, where the other kinds draw 2-5); with `--bundles`, last, 3-6 wires of
one colour laid side by side, 0.5-4 widths apart, through the frame or leaving it
(`bundles`: wires leaving a duct). One folder per kind, so that `ariadne eval --dataset DIR` reports each kind on its own row:

    training/.venv/bin/python scripts/stress.py /tmp/stress
    target/release/ariadne eval --dataset /tmp/stress --endpoints detect

With `--photos DIR`, a last kind, `photo`, draws the `textured` kind's cables on crops
of the photographs in DIR (any size, grey ones tinted): surfaces photographed, not
drawn, that neither the network nor this script's textures were made from: two crops
of each photograph, after every other kind (whose scenes stay as without it). Twelve
that scikit-image ships (brick, grass, gravel, the moon, coins, a stained tissue, a
printed page, handwriting, a photographer on a lawn, a café table, a garage, the deep
sky) come offline from PyPI:

    pip download --no-deps scikit-image -d /tmp/wheel
    unzip -o /tmp/wheel/scikit_image-*.whl 'skimage/data/*' -d /tmp/wheel
    mkdir -p /tmp/photos
    for f in brick grass gravel moon coins ihc page text camera coffee \
        motorcycle_left hubble_deep_field; do cp /tmp/wheel/skimage/data/$f.* /tmp/photos; done
    training/.venv/bin/python scripts/stress.py /tmp/stress --photos /tmp/photos

`photo-backgrounds.tsv` in the output folder names each `photo` scene's source.

Each photo has `NNNNN.jpg` (quality 90), its centrelines `NNNNN.txt` and 7 px masks
`NNNNN_mask_K.png` / `NNNNN_mask_all.png`, as the cables dataset (its README); a rod's
mask is as wide as the rod. Seeded:
the same scenes every run. These scenes are drawn, not photographed, and the bundled
network trained on drawn cables too: read them as a search for the engine's failures
on such backgrounds and layouts, not as a forecast for photos.
"""

import argparse
import math
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFilter

W, H = 640, 480
MASK_WIDTH = 7
# Ends closer to the border than this are where a cable leaves the frame (the
# dataset's convention); ends drawn in view are kept farther in.
INSIDE = 40.0

BACKGROUNDS = {
    "white": [(235, 235, 230), (222, 226, 232)],
    "grey": [(128, 128, 128), (150, 146, 140)],
    "black": [(22, 22, 25), (38, 36, 34)],
    "saturated": [(170, 40, 40), (40, 120, 60), (30, 40, 90), (220, 200, 60), (230, 130, 40)],
}
# One folder each: the background kinds, then thin rods, same-colour pairs, loops,
# textured surfaces and mixed widths (each appended, so the scenes before it stay as
# they were).
KINDS = list(BACKGROUNDS) + ["thin", "pairs", "loops", "textured", "mixed"]
# Drawn after every other kind, `photo` included, so that the sets drawn before it
# existed keep their scenes.
LATE_KINDS = ["crowded"]
# The `textured` kind's surfaces: a cutting mat's grid, perforated metal, cork or granite
# speckle, wooden planks, twill fabric, tiles with grout. Drawn here with their own
# rules, not those of training/scenes.py, so the kind tests more than the training
# scenes' textures.
TEXTURES = ["mat", "perforated", "speckle", "planks", "twill", "tiles"]
CABLE_COLOURS = [
    (220, 220, 215),  # white
    (35, 35, 38),  # black
    (200, 30, 30),
    (30, 60, 190),
    (30, 150, 50),
    (230, 120, 20),
    (240, 220, 40),
    (120, 70, 40),  # brown
    (150, 40, 160),
]


def smooth_path(rng, start, heading, steps, bend=1.0):
    """A path of 1 px steps from `start`, its heading driven by three slow sines (the
    tightest bends about 40 px in radius, `bend` times their amplitude)."""
    waves = [(bend * rng.uniform(-0.9, 0.9) / (k + 1), rng.uniform(0.5, 2.0) * (k + 1),
              rng.uniform(0.0, 2 * math.pi)) for k in range(3)]
    p = np.array(start, dtype=float)
    points = [p.copy()]
    for i in range(1, steps):
        s = i / 700.0
        theta = heading + sum(a * math.sin(f * s * math.pi + ph) for a, f, ph in waves)
        p = p + [math.cos(theta), math.sin(theta)]
        points.append(p.copy())
    return np.array(points)


def loop_cable(rng):
    """A cable that crosses itself once: it enters the frame, turns a full circle 30-70 px
    in radius, give or take 50° (all of the loop at least 20 px in view), and runs on
    out of the frame or to an end in view."""
    while True:
        side = rng.integers(4)
        start = [(rng.uniform(80, W - 80), 0.0), (W - 1.0, rng.uniform(80, H - 80)),
                 (rng.uniform(80, W - 80), H - 1.0), (0.0, rng.uniform(80, H - 80))][side]
        heading = [math.pi / 2, math.pi, -math.pi / 2, 0.0][side] + rng.uniform(-0.5, 0.5)
        radius = rng.uniform(30.0, 70.0)
        turn = rng.choice([-1.0, 1.0])
        # A full turn and up to about 50° more or less: the cable leaves the loop at
        # that angle to the way it came in, crossing itself at that angle.
        total = 2 * math.pi + rng.uniform(-0.9, 0.9)
        begin = rng.uniform(80.0, 220.0)
        span = 2 * math.pi * radius
        p = np.array(start, dtype=float)
        points = [p.copy()]
        drift = rng.uniform(-0.4, 0.4) / 600.0
        for i in range(1, 1400):
            t = min(max((i - begin) / span, 0.0), 1.0)
            theta = heading + drift * i + turn * total * t
            p = p + [math.cos(theta), math.sin(theta)]
            points.append(p.copy())
        path = np.array(points)
        loop = path[int(begin):int(begin + span)]
        out = next((i for i in range(5, len(path)) if not inside(path[i], 0.0)), None)
        if out is None or out < begin + span + 60 or not all(inside(q, 20.0) for q in loop):
            continue
        path = np.clip(path[:out], 0.0, [W - 1.0, H - 1.0])
        cut = int(rng.uniform(begin + span + 60, out + 60))
        if cut < out and inside(path[cut], INSIDE):
            return path[:cut]
        return path


def inside(p, margin):
    return margin <= p[0] <= W - 1 - margin and margin <= p[1] <= H - 1 - margin


def through_cable(rng):
    """A cable entering at one side of the frame and leaving at another, clipped to the
    frame (both ends on the border)."""
    while True:
        side = rng.integers(4)
        start = [(rng.uniform(80, W - 80), 0.0), (W - 1.0, rng.uniform(80, H - 80)),
                 (rng.uniform(80, W - 80), H - 1.0), (0.0, rng.uniform(80, H - 80))][side]
        heading = [math.pi / 2, math.pi, -math.pi / 2, 0.0][side] + rng.uniform(-0.6, 0.6)
        path = smooth_path(rng, start, heading, 1400)
        out = next((i for i in range(5, len(path)) if not inside(path[i], 0.0)), None)
        if out is not None and out > 250:
            return np.clip(path[:out], 0.0, [W - 1.0, H - 1.0])


def cable_in_view(rng):
    """A cable with both ends in view, at least 30 px from the border all along."""
    while True:
        start = (rng.uniform(INSIDE, W - INSIDE), rng.uniform(INSIDE, H - INSIDE))
        path = smooth_path(rng, start, rng.uniform(0, 2 * math.pi), int(rng.uniform(250, 650)))
        if all(inside(p, 30.0) for p in path):
            return path


def cable_leaving(rng):
    """A cable with one end in view and the other on the border."""
    path = through_cable(rng)
    cut = int(rng.uniform(0.35, 0.7) * len(path))
    if not inside(path[cut], INSIDE):
        return cable_in_view(rng)
    return path[:cut] if rng.random() < 0.5 else path[cut:][::-1]


def background(rng, kind):
    base = np.array(BACKGROUNDS[kind][rng.integers(len(BACKGROUNDS[kind]))], dtype=float)
    yy, xx = np.mgrid[0:H, 0:W]
    # Uneven light: a gentle gradient across the frame, and sensor noise.
    g = 1.0 + 0.12 * ((xx / W - 0.5) * rng.uniform(-1, 1) + (yy / H - 0.5) * rng.uniform(-1, 1))
    img = base[None, None, :] * g[:, :, None] + rng.normal(0.0, 3.0, (H, W, 3))
    return Image.fromarray(np.clip(img, 0, 255).astype(np.uint8))


def textured_background(rng):
    """One of `TEXTURES`, under the same uneven light and sensor noise as `background`."""
    kind = TEXTURES[rng.integers(len(TEXTURES))]
    yy, xx = np.mgrid[0:H, 0:W].astype(float)
    if kind == "mat":  # a coloured mat, light grid lines, every fifth bolder
        base = np.array([(40, 110, 70), (40, 60, 110), (60, 62, 66)][rng.integers(3)], float)
        img = np.ones((H, W, 3)) * base
        pitch = rng.uniform(12.0, 20.0)
        line = base * 0.4 + 150.0
        for axis in (xx, yy):
            k = axis / pitch
            near = np.abs(k - np.round(k)) * pitch
            bold = np.round(k) % 5 == 0
            on = (near < 0.6) | (bold & (near < 1.2))
            img[on] = line
    elif kind == "perforated":  # bright metal, a staggered grid of dark holes
        img = np.ones((H, W, 3)) * rng.uniform(140.0, 200.0) * rng.uniform(0.95, 1.05, 3)
        img += np.cumsum(rng.normal(0.0, 1.0, (H, W)), axis=1)[..., None] * 0.15
        pitch, radius = rng.uniform(10.0, 18.0), rng.uniform(2.0, 3.5)
        row = np.round(yy / pitch)
        dx = xx - (np.round(xx / pitch - (row % 2) * 0.5) + (row % 2) * 0.5) * pitch
        img[np.hypot(dx, yy - row * pitch) < radius] = 30.0
    elif kind == "speckle":  # cork or granite: dense small flecks of related colours
        bases = [(180, 140, 95), (120, 120, 118), (200, 195, 185), (60, 58, 55)]
        base = np.array(bases[rng.integers(4)], float)
        img = np.ones((H, W, 3)) * base
        for shade in rng.uniform(0.55, 1.4, 3):
            flecks = rng.random((H // 2, W // 2)) < rng.uniform(0.05, 0.2)
            big = np.kron(flecks, np.ones((2, 2), bool))
            img[big] = np.clip(base * shade, 0, 255)
    elif kind == "planks":  # wood grain along one axis, dark seams between planks
        base = np.array([(190, 145, 95), (150, 100, 60), (215, 185, 140)][rng.integers(3)], float)
        along, across = (xx, yy) if rng.random() < 0.5 else (yy, xx)
        width = rng.uniform(60.0, 130.0)
        plank = np.floor(across / width)
        warp = np.sin(along / rng.uniform(40.0, 90.0) + plank * 1.7) * rng.uniform(2.0, 6.0)
        grain = np.sin((across + warp) * rng.uniform(0.4, 1.2) + plank * 2.3)
        img = base * (1.0 + 0.08 * grain[..., None] + 0.06 * np.sin(plank * 3.1)[..., None])
        img[np.abs(across - np.round(across / width) * width) < 1.2] = base * 0.35
    elif kind == "twill":  # diagonal ribs of a woven cloth
        bases = [(40, 50, 90), (110, 110, 115), (150, 40, 45), (200, 190, 170)]
        base = np.array(bases[rng.integers(4)], float)
        pitch = rng.uniform(3.0, 6.0)
        ribs = np.sin((xx + yy) * math.pi / pitch) * np.sin((xx - 2 * yy) * math.pi / (3 * pitch))
        img = base * (1.0 + 0.18 * ribs[..., None])
    else:  # tiles: squares of two close colours, grey grout
        base = np.array([(225, 225, 220), (60, 90, 140), (170, 80, 60)][rng.integers(3)], float)
        size = rng.uniform(40.0, 80.0)
        check = ((np.floor(xx / size) + np.floor(yy / size)) % 2)[..., None]
        img = base * (1.0 - 0.08 * check)
        grout = np.zeros((H, W), bool)
        for axis in (xx, yy):
            grout |= np.abs(axis - np.round(axis / size) * size) < 1.5
        img[grout] = (128.0, 125.0, 120.0)
    g = 1.0 + 0.12 * ((xx / W - 0.5) * rng.uniform(-1, 1) + (yy / H - 0.5) * rng.uniform(-1, 1))
    img = img * g[:, :, None] + rng.normal(0.0, 3.0, (H, W, 3))
    return Image.fromarray(np.clip(img, 0, 255).astype(np.uint8))


def photo_background(rng, path):
    """A random crop of the photograph at `path`, enlarged 1-1.3x beyond covering the
    frame; a grey photograph tinted, under the same sensor noise as `background`."""
    photo = Image.open(path)
    grey = photo.mode in ("L", "LA", "I", "I;16")
    photo = photo.convert("RGB")
    scale = max(W / photo.width, H / photo.height) * rng.uniform(1.0, 1.3)
    size = (math.ceil(photo.width * scale), math.ceil(photo.height * scale))
    photo = photo.resize(size, Image.BICUBIC)
    x0, y0 = rng.integers(0, size[0] - W + 1), rng.integers(0, size[1] - H + 1)
    img = np.asarray(photo.crop((x0, y0, x0 + W, y0 + H)), float)
    if grey:
        img = img * rng.uniform(0.6, 1.15, 3)
    return Image.fromarray(np.clip(img + rng.normal(0.0, 2.0, img.shape), 0, 255).astype(np.uint8))


def cast_shadows(img, paths, widths, rng):
    """Darkens `img` under each path moved 2-4 px down and right, blurred: the soft
    shadow a cable casts on a flat surface lit from above and to one side."""
    shade = Image.new("L", (W, H), 0)
    d = ImageDraw.Draw(shade)
    off = rng.uniform(2.0, 4.0, 2)
    for path, width in zip(paths, widths):
        d.line([tuple(p + off) for p in path], fill=255, width=int(round(width + 2)), joint="curve")
    s = np.asarray(shade.filter(ImageFilter.GaussianBlur(2.5)), float)[..., None] / 255.0
    dark = np.asarray(img, float) * (1.0 - rng.uniform(0.3, 0.5) * s)
    return Image.fromarray(np.clip(dark, 0, 255).astype(np.uint8))


def rim_of(colour):
    """The darker colour of a cable's or rod's rim."""
    return tuple(int(c * 0.55) for c in colour)


def draw_cable(draw, path, colour, width):
    """A shaded cable along `path`, a metal terminal beyond each end in view."""
    pts = [tuple(p) for p in path]
    rim = rim_of(colour)
    core = tuple(min(255, int(c * 1.25 + 25)) for c in colour)
    for w, c in ((width, rim), (width - 3, colour), (3, core)):
        draw.line(pts, fill=c, width=int(round(w)), joint="curve")
    for end, before in ((path[0], path[min(8, len(path) - 1)]), (path[-1], path[max(-9, -len(path))])):
        if inside(end, INSIDE - 1):
            d = (end - before) / max(np.linalg.norm(end - before), 1e-3)
            tip = end + d * 14.0
            draw.line([tuple(end), tuple(tip)], fill=(175, 170, 160), width=int(round(width - 4)))


def draw_rod(draw, path, colour, width):
    """A thin rod along `path` (under 7 px): a darker rim around its colour, blunt ends."""
    pts = [tuple(p) for p in path]
    rim = rim_of(colour)
    draw.line(pts, fill=rim, width=int(round(width)), joint="curve")
    draw.line(pts, fill=colour, width=max(1, int(round(width - 2))), joint="curve")


def add_cables(rng, draw, lines, count, make_path, widths):
    """Draws `count` shaded cables along `make_path(rng)`, each of a random colour and a
    width uniform in `widths`, and adds them to `lines` with the dataset's mask width."""
    for _ in range(count):
        path = make_path(rng)
        colour = CABLE_COLOURS[rng.integers(len(CABLE_COLOURS))]
        draw_cable(draw, path, colour, rng.uniform(*widths))
        lines.append((path, MASK_WIDTH))


def any_cable(rng):
    """A cable through the frame (35 %), leaving it at one end (25 %) or all in view."""
    r = rng.random()
    return through_cable(rng) if r < 0.35 else cable_leaving(rng) if r < 0.6 else cable_in_view(rng)


def parallel(path, offset):
    """`path` moved `offset` px along its normal (either side by the sign), cut to its
    longest run inside the frame."""
    d = np.gradient(path, axis=0)
    n = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.maximum(np.linalg.norm(d, axis=1), 1e-6)[:, None]
    moved = path + offset * n
    ok = np.array([inside(p, 0.0) for p in moved])
    best, start = (0, 0), None
    for i, v in enumerate(list(ok) + [False]):
        if v and start is None:
            start = i
        elif not v and start is not None:
            best = max(best, (i - start, start))
            start = None
    return moved[best[1]:best[1] + best[0]]


def add_bundle(rng, draw, lines):
    """3-6 straight or gently bent wires of one colour laid side by side, 0.5-4 widths
    apart, through the frame or leaving it at one end (their ends in view staggered,
    each with a metal terminal): wires leaving a duct or a harness."""
    while True:
        side = rng.integers(4)
        start = [(rng.uniform(160, W - 160), 0.0), (W - 1.0, rng.uniform(160, H - 160)),
                 (rng.uniform(160, W - 160), H - 1.0), (0.0, rng.uniform(160, H - 160))][side]
        heading = [math.pi / 2, math.pi, -math.pi / 2, 0.0][side] + rng.uniform(-0.4, 0.4)
        # Begun 150 px outside the frame, so that every wire, cut to the frame by
        # `parallel`, enters it at its edge.
        back = np.array(start) - 150.0 * np.array([math.cos(heading), math.sin(heading)])
        base = smooth_path(rng, back, heading, 1600, bend=0.3)
        if sum(inside(p, 0.0) for p in base) > 250:
            break
    count = int(rng.integers(3, 7))
    colour = CABLE_COLOURS[rng.integers(len(CABLE_COLOURS))]
    width = rng.uniform(7.0, 11.0)
    pitch = width * rng.uniform(1.5, 5.0)
    ending = rng.random() < 0.5
    for k in range(count):
        line = parallel(base, (k - (count - 1) / 2) * pitch)
        if ending:
            cut = int(len(line) * rng.uniform(0.45, 0.7))
            line = line[:cut]
        if len(line) > 100:
            draw_cable(draw, line, colour, width)
            lines.append((line, MASK_WIDTH))


def scene(rng, kind):
    """A photo of `kind` and its centrelines with their mask widths: a background kind
    with cables 7-11 px wide; `thin`, rods 3-5 px wide; `pairs`, one or two pairs of
    same-colour cables side by side (0-4 px apart) among others; `loops`, cables that
    loop over themselves; `mixed`, power cables 14-22 px wide among wires 5-8 px wide.
    Those four on any background kind; `textured` has its own surfaces
    (`textured_scene`). Masks are the dataset's 7 px strokes (a power cable's too: the
    dataset draws one width for every cable), but a rod's is as wide as the rod: a 7 px
    stroke would be wider than the object."""
    lines = []
    if kind == "textured":
        return textured_scene(rng)
    backdrop = kind if kind in BACKGROUNDS else list(BACKGROUNDS)[rng.integers(len(BACKGROUNDS))]
    img = background(rng, backdrop)
    draw = ImageDraw.Draw(img)
    if kind == "pairs":
        for _ in range(int(rng.integers(1, 3))):
            path = through_cable(rng) if rng.random() < 0.5 else cable_in_view(rng)
            colour = CABLE_COLOURS[rng.integers(len(CABLE_COLOURS))]
            width = rng.uniform(7.0, 11.0)
            twin = parallel(path, (width + rng.uniform(0.0, 4.0)) * rng.choice([-1.0, 1.0]))
            for line in (path, twin):
                if len(line) > 100:
                    draw_cable(draw, line, colour, width)
                    lines.append((line, MASK_WIDTH))
    if kind == "mixed":
        add_cables(rng, draw, lines, int(rng.integers(1, 3)), any_cable, (14.0, 22.0))
        add_cables(rng, draw, lines, int(rng.integers(2, 5)), any_cable, (5.0, 8.0))
    if kind == "loops":
        add_cables(rng, draw, lines, int(rng.integers(1, 3)), loop_cable, (7.0, 11.0))
    if kind == "crowded":
        add_cables(rng, draw, lines, int(rng.integers(6, 11)), any_cable, (7.0, 11.0))
    if kind == "bundles":
        add_bundle(rng, draw, lines)
    if kind in ("mixed", "crowded"):
        extra = 0
    elif kind in ("pairs", "loops", "bundles"):
        extra = rng.integers(0, 3)
    else:
        extra = rng.integers(2, 6)
    if kind == "thin":
        for _ in range(int(extra)):
            path = any_cable(rng)
            colour = CABLE_COLOURS[rng.integers(len(CABLE_COLOURS))]
            width = rng.uniform(3.0, 5.0)
            draw_rod(draw, path, colour, width)
            lines.append((path, int(round(width))))
    else:
        add_cables(rng, draw, lines, int(extra), any_cable, (7.0, 11.0))
    return img.filter(ImageFilter.GaussianBlur(0.7)), lines


def textured_scene(rng, photo=None):
    """A `textured` photo: 2-5 cables 7-11 px wide, each casting a soft shadow, on one of
    `TEXTURES`, or on a crop of the photograph at `photo`."""
    img = textured_background(rng) if photo is None else photo_background(rng, photo)
    paths = [any_cable(rng) for _ in range(int(rng.integers(2, 6)))]
    widths = [rng.uniform(7.0, 11.0) for _ in paths]
    img = cast_shadows(img, paths, widths, rng)
    draw = ImageDraw.Draw(img)
    for path, width in zip(paths, widths):
        draw_cable(draw, path, CABLE_COLOURS[rng.integers(len(CABLE_COLOURS))], width)
    return img.filter(ImageFilter.GaussianBlur(0.7)), [(path, MASK_WIDTH) for path in paths]


def mask(lines):
    m = Image.new("L", (W, H), 0)
    d = ImageDraw.Draw(m)
    for path, width in lines:
        d.line([tuple(p) for p in path], fill=255, width=width, joint="curve")
    return m


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--per-kind", type=int, default=12, help="photos per background kind")
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--photos", type=Path,
                    help="a folder of photographs: adds the `photo` kind, cables on them")
    ap.add_argument("--bundles", action="store_true",
                    help="adds the `bundles` kind, drawn last: wires of one colour side by side")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    photos = []
    if args.photos:
        photos = sorted(p for p in args.photos.iterdir()
                        if p.suffix.lower() in (".png", ".jpg", ".jpeg"))
    sources = []
    extra = ["bundles"] if args.bundles else []
    for kind in KINDS + (["photo"] if photos else []) + LATE_KINDS + extra:
        folder = args.out / kind
        folder.mkdir(parents=True, exist_ok=True)
        for i in range(2 * len(photos) if kind == "photo" else args.per_kind):
            name = f"{i:05d}"
            if kind == "photo":
                source = photos[i // 2]
                sources.append(f"{name}\t{source.name}\n")
                img, lines = textured_scene(rng, source)
            else:
                img, lines = scene(rng, kind)
            img.save(folder / f"{name}.jpg", quality=90)
            with open(folder / f"{name}.txt", "w") as f:
                for path, _ in lines:
                    keep = list(range(0, len(path), max(1, len(path) // 40)))
                    keep += [] if keep[-1] == len(path) - 1 else [len(path) - 1]
                    pts = path[keep].tolist()
                    f.write(f"{len(pts)} " + " ".join(f"{x:.1f} {y:.1f}" for x, y in pts) + "\n")
            mask(lines).save(folder / f"{name}_mask_all.png")
            for k, line in enumerate(lines):
                mask([line]).save(folder / f"{name}_mask_{k}.png")
    if sources:
        (args.out / "photo-backgrounds.tsv").write_text("".join(sources))
    count = (len(KINDS) + len(LATE_KINDS) + len(extra)) * args.per_kind + 2 * len(photos)
    print(f"{count} photos under {args.out}")


if __name__ == "__main__":
    main()
