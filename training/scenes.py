"""Training scenes for the cable field: the development photos, their cables composed
onto procedural backgrounds, and procedurally drawn cables, with dense targets.

Everything works at the network's input resolution (half the photo's: 320x240 for a
640x480 photo). A scene is an RGB float image in [0, 255], a cable mask in [0, 1], the
cables' centrelines (for orientation targets) and their terminals (ends off the
border). Backgrounds and cables are meant to span what a factory camera may see
(white to black, saturated card, wood, paper, fabric, brushed metal, printed clutter,
gradients, shadows), not the three backgrounds of the development split.
"""

from __future__ import annotations

import colorsys
import io
import math
import random
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFilter

from groups import background_group

INPUT_SCALE = 0.5  # the network sees the photo at half resolution
IN_W, IN_H = 320, 240
# Ends this close to the border (photo pixels) are where a cable leaves the frame, not
# terminals (same rule as the Rust evaluator, src/eval/dataset.rs).
BORDER_TOLERANCE_PX = 12.0


@dataclass
class Scene:
    rgb: np.ndarray  # H x W x 3 float32, 0..255
    mask: np.ndarray  # H x W float32, 0..1: cable body
    lines: list = field(default_factory=list)  # centrelines, each an N x 2 array (input px)
    ends: list = field(default_factory=list)  # terminals (input px)


@dataclass
class Photo:
    set: str
    name: str
    group: str
    rgb: np.ndarray  # input resolution
    mask: np.ndarray
    lines: list
    ends: list


# ---------------------------------------------------------------------------------------
# The development split.


def read_lines(txt: Path) -> list[np.ndarray]:
    lines = []
    for row in txt.read_text().splitlines():
        v = row.split()
        if not v:
            continue
        k = int(v[0])
        lines.append(np.array([[float(v[1 + 2 * i]), float(v[2 + 2 * i])] for i in range(k)]))
    return lines


def terminals(lines, width: float, height: float, tol: float) -> list[tuple[float, float]]:
    out = []
    for pts in lines:
        for x, y in (pts[0], pts[-1]):
            if tol <= x <= width - 1 - tol and tol <= y <= height - 1 - tol:
                out.append((float(x), float(y)))
    return out


def load_photos(root: Path) -> list[Photo]:
    photos = []
    for set_name in ("simple", "hard"):
        for jpg in sorted((root / set_name).glob("*.jpg")):
            image = Image.open(jpg).convert("RGB")
            w, h = image.size
            lines = read_lines(jpg.with_suffix(".txt"))
            ends = terminals(lines, w, h, BORDER_TOLERANCE_PX)
            size = (round(w * INPUT_SCALE), round(h * INPUT_SCALE))
            rgb = np.asarray(image.resize(size, Image.BILINEAR), np.float32)
            mask_img = Image.open(jpg.with_name(jpg.stem + "_mask_all.png")).convert("L")
            mask = np.asarray(mask_img.resize(size, Image.BILINEAR), np.float32) / 255.0
            photos.append(Photo(
                set=set_name, name=jpg.stem, group=background_group(set_name, jpg.stem),
                rgb=rgb, mask=mask,
                lines=[p * INPUT_SCALE for p in lines],
                ends=[(x * INPUT_SCALE, y * INPUT_SCALE) for x, y in ends]))
    return photos


def photo_scene(p: Photo) -> Scene:
    return Scene(p.rgb.copy(), p.mask.copy(), [l.copy() for l in p.lines], list(p.ends))


# ---------------------------------------------------------------------------------------
# Procedural backgrounds.


def random_colour(rng: random.Random, lightness=None) -> np.ndarray:
    h = rng.random()
    s = rng.choice([0.0, rng.uniform(0, 0.3), rng.uniform(0.3, 1.0)])
    v = rng.uniform(0.02, 1.0) if lightness is None else lightness
    return np.array(colorsys.hsv_to_rgb(h, s, v), np.float32) * 255


def smooth_noise(nrng: np.random.Generator, h: int, w: int, scale: float) -> np.ndarray:
    """Value noise in [-1, 1] with features about `scale` pixels across."""
    gh, gw = max(2, int(h / scale) + 2), max(2, int(w / scale) + 2)
    small = Image.fromarray(nrng.uniform(-1, 1, (gh, gw)).astype(np.float32))
    return np.asarray(small.resize((w, h), Image.BICUBIC), np.float32).clip(-1.5, 1.5)


# Also draw the busy textures (`mosaic`, `drips`): train_field.py's `--rich-textures`,
# on for the bundled model (`--no-rich-textures` leaves them out).
RICH_TEXTURES = False

# Share of composed and procedural scenes where one cable wears the background's colour
# (a pale cable on pale card, a black one on dark paper, a red one on a red print):
# train_field.py's `--camouflage`.
CAMOUFLAGE = 0.0

# Chance that a procedural cable's end wears an insulated sleeve (a bootlace ferrule or a
# crimp terminal's barrel: a short, wider collar of its own colour, often followed by
# metal), as switchgear wiring does: train_field.py's `--sleeves`.
SLEEVES = 0.0

# Share of procedural backgrounds drawn with lines that are not cables: masonry and
# tiles whose joints are as wide as a cable, or handwriting (train_field.py's
# `--line-textures`). Their lines are straight and periodic, with T-junctions, or short,
# soft and tightly curved; a cable is none of these.
LINE_TEXTURES = 0.0

# Chance that a procedural cable drawn after another ends against it (train_field.py's
# `--abutting`): its tip on, or just beside, a cable already drawn, as where cables lie
# in a heap. The development photos have no terminal within 20 px of another cable, so
# the network learnt ends only on free ground (models/README.md, "Ends against other
# cables").
ABUTTING = 0.0


# Share of procedural backgrounds that are a crop of a photograph (train_field.py's
# `--photo-textures`, with `--background-photos DIR`): real surfaces, objects and their
# edges, none of them a cable. `BACKGROUND_PHOTOS` holds the photographs, RGB arrays.
PHOTO_TEXTURES = 0.0
BACKGROUND_PHOTOS: list[np.ndarray] = []

# Chance that a procedural cable comes with 2-4 more of its colour laid beside it, one
# after another, 0.6-3 widths of gap apart (train_field.py's `--bundles`): wires leaving
# a duct or a harness side by side. Without them the only straight, parallel, evenly
# spaced lines the network saw were masonry joints, and it reads real wires so laid
# weakly (models/README.md, "Wires laid side by side").
BUNDLES = 0.0


def load_background_photos(folder: Path) -> list[np.ndarray]:
    """Every JPEG and PNG photograph in `folder`, as RGB arrays, in name order."""
    files = sorted(f for f in folder.iterdir() if f.suffix.lower() in (".jpg", ".png"))
    return [np.asarray(Image.open(f).convert("RGB")) for f in files]


def photo_crop(rng: random.Random, h: int, w: int) -> np.ndarray:
    """A crop of one of `BACKGROUND_PHOTOS`, from a third of the photograph's extent
    to all of it, flipped or turned at random, resized to `w` x `h`; grey at times."""
    src = rng.choice(BACKGROUND_PHOTOS)
    if rng.random() < 0.5:
        src = np.rot90(src)
    sh, sw = src.shape[:2]
    fit = min(sh / h, sw / w)
    s = fit * rng.uniform(0.33, 1.0)
    ch, cw = max(2, int(h * s)), max(2, int(w * s))
    y, x = rng.randrange(sh - ch + 1), rng.randrange(sw - cw + 1)
    crop = Image.fromarray(np.ascontiguousarray(src[y:y + ch, x:x + cw]))
    img = np.asarray(crop.resize((w, h), Image.BILINEAR), np.float32)
    if rng.random() < 0.5:
        img = img[:, ::-1]
    if rng.random() < 0.25:
        img = np.repeat(img.mean(axis=2, keepdims=True), 3, axis=2)
    return np.ascontiguousarray(img)


def option_drawn(rng: random.Random, share: float) -> bool:
    """True with probability `share`, for an option that is off by default: at 0 it
    draws no random number, so the recipe's scenes stay those the bundled model saw
    (model card, Training; `make scene-check`)."""
    return share > 0 and rng.random() < share


def background(rng: random.Random, h=IN_H, w=IN_W, base=None) -> np.ndarray:
    """A procedural background; `base`, when given, is its main colour."""
    nrng = np.random.default_rng(rng.randrange(1 << 30))
    kinds = ["plain", "plain", "gradient", "wood", "paper", "fabric", "metal", "noise",
             "clutter", "clutter"]
    if RICH_TEXTURES:
        kinds += ["mosaic", "mosaic", "drips", "drips"]
    if option_drawn(rng, LINE_TEXTURES):
        kind = "lines"
    elif option_drawn(rng, PHOTO_TEXTURES):
        kind = "photo"
    else:
        kind = rng.choice(kinds)
    base = random_colour(rng) if base is None else base
    img = np.ones((h, w, 3), np.float32) * base
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    if kind == "gradient":
        other = random_colour(rng)
        a = rng.uniform(0, math.pi)
        t = (xx * math.cos(a) + yy * math.sin(a))
        t = (t - t.min()) / (np.ptp(t) + 1e-6)
        img = img * (1 - t[..., None]) + other * t[..., None]
    elif kind == "wood":
        a = rng.uniform(0, math.pi)
        u = xx * math.cos(a) + yy * math.sin(a)
        warp = smooth_noise(nrng, h, w, rng.uniform(20, 80)) * rng.uniform(5, 25)
        grain = np.sin((u + warp) * rng.uniform(0.15, 0.6))
        dark = random_colour(rng) * 0.5 + base * 0.5
        t = (grain * 0.5 + 0.5)[..., None] * rng.uniform(0.3, 1.0)
        img = img * (1 - t) + dark * t
    elif kind == "paper":
        img = img + smooth_noise(nrng, h, w, rng.uniform(2, 6))[..., None] * rng.uniform(3, 12)
    elif kind == "fabric":
        p = rng.uniform(2, 6)
        weave = np.sin(xx * math.pi / p) * np.sin(yy * math.pi / p)
        img = img + weave[..., None] * rng.uniform(8, 40)
        img = img + nrng.normal(0, 6, (h, w, 1)).astype(np.float32)
    elif kind == "metal":
        grey = rng.uniform(60, 220)
        img = np.ones((h, w, 3), np.float32) * grey * nrng.uniform(0.9, 1.1, 3).astype(np.float32)
        axis = rng.choice([0, 1])  # brushed along rows or columns
        streak = nrng.normal(0, 1, (h, w)).astype(np.float32).cumsum(axis=axis)
        streak = (streak - streak.mean(axis=axis, keepdims=True)) / (streak.std() + 1e-6)
        img = img + streak[..., None] * rng.uniform(3, 15)
    elif kind == "noise":
        other = random_colour(rng)
        t = (smooth_noise(nrng, h, w, rng.uniform(3, 40)) * 0.5 + 0.5)[..., None]
        img = img * (1 - t) + other * t
    elif kind == "mosaic":  # shaded coloured tiles
        tile = rng.randrange(8, 30)
        for ty in range(0, h, tile):
            for tx in range(0, w, tile):
                c = random_colour(rng, rng.uniform(0.3, 1.0))
                shade = np.linspace(1.2, 0.6, min(tile, w - tx))[None, :, None]
                img[ty:ty + tile, tx:tx + tile] = c * shade
    elif kind == "drips":  # dense thin tangled strokes, many colours (drip painting)
        pil = Image.fromarray(np.clip(img, 0, 255).astype(np.uint8))
        d = ImageDraw.Draw(pil)
        for _ in range(rng.randrange(40, 160)):
            pts = np.cumsum(nrng.normal(0, 6, (rng.randrange(4, 20), 2)), axis=0)
            pts += (rng.uniform(0, w), rng.uniform(0, h))
            d.line([tuple(p) for p in pts], fill=tuple(int(v) for v in random_colour(rng)),
                   width=rng.randrange(1, 3))
        img = np.asarray(pil, np.float32)
    elif kind == "lines":
        img = masonry(rng, nrng, base) if rng.random() < 0.6 else handwriting(rng, nrng, img)
    elif kind == "photo":
        img = photo_crop(rng, h, w)
    if kind == "clutter" or rng.random() < 0.25:
        img = clutter(rng, img)
    if rng.random() < 0.35:  # shadows and uneven light
        light = 1 + smooth_noise(nrng, h, w, rng.uniform(40, 160)) * rng.uniform(0.1, 0.5)
        img = img * light[..., None]
    return np.clip(img, 0, 255)


def masonry(rng: random.Random, nrng: np.random.Generator, base: np.ndarray,
            h=IN_H, w=IN_W) -> np.ndarray:
    """Bricks in running bond, or square tiles, at any angle, each a little lighter or
    darker than `base`, with joints 1-4 px wide (2-8 photo px: a cable's width) of
    another colour."""
    a = rng.uniform(0, math.pi)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    u = xx * math.cos(a) + yy * math.sin(a) + rng.uniform(0, 100)
    v = -xx * math.sin(a) + yy * math.cos(a) + rng.uniform(0, 100)
    course = rng.uniform(6, 30)
    tiles = rng.random() < 0.3
    length = course if tiles else min(90.0, course * rng.uniform(2, 4))
    joint = rng.uniform(1.0, 4.0)
    row = np.floor(v / course)
    shifted = u + (0 if tiles else (row % 2) * length / 2)
    col = np.floor(shifted / length)
    shade = nrng.uniform(0.85, 1.15, 997).astype(np.float32)
    brick = shade[((row * 31 + col * 17) % 997).astype(np.int64)]
    img = base * brick[..., None]
    on = (v - row * course < joint) | (shifted - col * length < joint)
    mortar = rng.choice([base * rng.uniform(0.3, 0.7), base * 0.4 + 255 * 0.6,
                         random_colour(rng)])
    img[on] = mortar
    return img + nrng.normal(0, 4, (h, w, 1)).astype(np.float32)


def handwriting(rng: random.Random, nrng: np.random.Generator, img: np.ndarray
                ) -> np.ndarray:
    """Rows of handwriting at any angle: short, tightly curved strokes 1-3 px wide in
    one ink, softened by a blur."""
    h, w = img.shape[:2]
    ink = Image.new("L", (w, h), 0)
    d = ImageDraw.Draw(ink)
    a = rng.uniform(0, math.pi)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    pitch, size = rng.uniform(12, 40), rng.uniform(4, 12)
    span = math.hypot(w, h)
    for r in np.arange(-span / 2, span / 2, pitch):
        x = -span / 2 + rng.uniform(0, pitch)
        while x < span / 2:
            if rng.random() < 0.6:  # a word: a few strokes that turn sharply
                heading = rng.uniform(0, 2 * math.pi)
                turns = nrng.normal(0, 1.2, rng.randrange(3, 9)).cumsum() + heading
                steps = size * 0.6 * np.stack([np.cos(turns), np.sin(turns)], 1)
                pts = np.array([x, r]) + np.vstack([[0, 0], steps.cumsum(0)])
                pts = pts @ rot.T + (w / 2, h / 2)
                d.line([tuple(p) for p in pts], fill=255, width=rng.randrange(1, 4))
            x += size * rng.uniform(1, 3)
    alpha = np.asarray(ink.filter(ImageFilter.GaussianBlur(rng.uniform(0.3, 1.2))),
                       np.float32)[..., None] / 255
    colour = rng.choice([np.array([20, 20, 30]), np.array([20, 40, 140]),
                         random_colour(rng)])
    return img * (1 - alpha) + colour * alpha


def clutter(rng: random.Random, img: np.ndarray) -> np.ndarray:
    """Printed clutter: shapes, short strokes, text-like rows; never long smooth tubes."""
    h, w = img.shape[:2]
    pil = Image.fromarray(np.clip(img, 0, 255).astype(np.uint8))
    d = ImageDraw.Draw(pil)
    for _ in range(rng.randrange(5, 60)):
        c = tuple(int(v) for v in random_colour(rng))
        x, y = rng.uniform(0, w), rng.uniform(0, h)
        r = rng.uniform(2, 30)
        kind = rng.random()
        if kind < 0.3:
            d.ellipse((x - r, y - r, x + r, y + r), fill=c)
        elif kind < 0.55:
            d.rectangle((x - r, y - r * rng.uniform(0.2, 1), x + r, y + r), fill=c)
        elif kind < 0.8:
            d.line((x, y, x + rng.uniform(-40, 40), y + rng.uniform(-40, 40)), fill=c,
                   width=rng.randrange(1, 3))
        else:  # a row of "letters"
            for k in range(rng.randrange(3, 12)):
                cw = rng.uniform(1.5, 4)
                d.rectangle((x + k * cw * 1.6, y, x + k * cw * 1.6 + cw, y + cw * 1.8), fill=c)
    return np.asarray(pil, np.float32)


# ---------------------------------------------------------------------------------------
# Procedural cables.


def catmull_rom(points: np.ndarray, per_segment=24) -> np.ndarray:
    p = np.vstack([points[0], points, points[-1]])
    out = []
    t = np.linspace(0, 1, per_segment, endpoint=False)[:, None]
    for i in range(1, len(p) - 2):
        p0, p1, p2, p3 = p[i - 1], p[i], p[i + 1], p[i + 2]
        out.append(0.5 * ((2 * p1) + (-p0 + p2) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t**2
                          + (-p0 + 3 * p1 - 3 * p2 + p3) * t**3))
    out.append(p[-2][None])
    return np.vstack(out)


def random_path(rng: random.Random, h=IN_H, w=IN_W) -> np.ndarray:
    """A smooth random centreline (input px), sometimes leaving the frame, sometimes
    looping over itself."""
    margin = 40 if rng.random() < 0.4 else -10
    n = rng.randrange(3, 7)
    x, y = rng.uniform(-margin, w + margin), rng.uniform(-margin, h + margin)
    heading = rng.uniform(0, 2 * math.pi)
    pts = [(x, y)]
    loop_at = rng.randrange(1, n) if rng.random() < 0.2 else -1
    for i in range(n):
        if i == loop_at:  # a tight loop: the cable crosses itself
            r = rng.uniform(10, 30)
            turn = rng.choice([-1, 1])
            cx, cy = x + r * math.cos(heading + turn * math.pi / 2), y + r * math.sin(heading + turn * math.pi / 2)
            for k in range(1, 6):
                a = heading - turn * math.pi / 2 + turn * k * 2 * math.pi / 5 * 1.15
                pts.append((cx + r * math.cos(a), cy + r * math.sin(a)))
            x, y = pts[-1]
            heading += turn * 2 * math.pi * 1.15
        heading += rng.uniform(-0.9, 0.9)
        step = rng.uniform(30, 90)
        x, y = x + step * math.cos(heading), y + step * math.sin(heading)
        pts.append((x, y))
    return catmull_rom(np.array(pts))


def draw_cable(scene: Scene, path: np.ndarray, rng: random.Random, colour=None, width=None,
               terminals_p=0.7, tipped=()):
    """Draws a shaded cable with a darker rim along `path` (input px), supersampled 2x,
    updating the mask, centrelines and terminals. Ends in view get a metal terminal
    with chance `terminals_p`, those listed in `tipped` (0: the start, 1: the last
    point) always."""
    h, w = scene.mask.shape
    ss = 2
    width = width if width is not None else rng.uniform(2.5, 8.0)
    colour = colour if colour is not None else random_colour(rng)
    rim = colour * rng.uniform(0.3, 0.7)
    light = np.minimum(colour * 1.3 + 40, 255)
    layer = Image.new("RGB", (w * ss, h * ss))
    alpha = Image.new("L", (w * ss, h * ss))
    body = Image.new("L", (w * ss, h * ss))
    dl, da, db = ImageDraw.Draw(layer), ImageDraw.Draw(alpha), ImageDraw.Draw(body)
    pts = [tuple(p) for p in path * ss]
    wpx = width * ss
    rimmed_stroke(dl, da, pts, colour, rim, wpx)
    if rng.random() < 0.7:
        off = wpx * 0.15
        dl.line([(x - off, y - off) for x, y in pts], fill=tuple(int(v) for v in light),
                width=max(1, round(wpx * 0.2)))
    db.line(pts, fill=255, width=max(1, round(wpx)))
    ends = []
    heads = ((path[0], path[min(3, len(path) - 1)]), (path[-1], path[max(-4, -len(path))]))
    for i, (end, prev) in enumerate(heads):
        tol = BORDER_TOLERANCE_PX * INPUT_SCALE
        if not (tol <= end[0] <= w - 1 - tol and tol <= end[1] <= h - 1 - tol):
            continue
        ends.append((float(end[0]), float(end[1])))
        if option_drawn(rng, SLEEVES):
            draw_sleeve(dl, da, path, i == 0, wpx, ss, rng)
        if rng.random() < terminals_p or i in tipped:  # metal beyond the insulation
            d = end - prev
            d = d / (np.linalg.norm(d) + 1e-9)
            tip = (end + d * rng.uniform(5, 15)) * ss
            grey = rng.uniform(110, 235)
            metal = tuple(int(grey * k) for k in (1.0, rng.uniform(0.85, 1.0), rng.uniform(0.6, 1.0)))
            tw = max(2, round(wpx * rng.uniform(0.5, 0.9)))
            dl.line((end[0] * ss, end[1] * ss, tip[0], tip[1]), fill=metal, width=tw)
            da.line((end[0] * ss, end[1] * ss, tip[0], tip[1]), fill=255, width=tw)
    size = (w, h)
    layer = np.asarray(layer.resize(size, Image.BOX), np.float32)
    a = np.asarray(alpha.resize(size, Image.BOX), np.float32)[..., None] / 255
    b = np.asarray(body.resize(size, Image.BOX), np.float32) / 255
    # Premultiplied: the layer is black outside the strokes.
    scene.rgb = scene.rgb * (1 - a) + layer
    # A cable drawn over another hides it: the mask is the union, as annotated.
    scene.mask = np.maximum(scene.mask, b)
    scene.lines.append(path.copy())
    scene.ends.extend(ends)


def draw_sleeve(dl: ImageDraw.ImageDraw, da: ImageDraw.ImageDraw, path: np.ndarray,
                at_start: bool, wpx: float, ss: int, rng: random.Random):
    """Draws an insulated sleeve over the last 1.5-4 widths of `path` (its start when
    `at_start`) on the supersampled layer `dl` and alpha `da`: 1-1.6 times as wide as
    the cable (`wpx` supersampled px), of a random colour, with a darker rim."""
    pts = path if at_start else path[::-1]
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    length = wpx / ss * rng.uniform(1.5, 4.0)
    collar = [tuple(p * ss) for p in pts[arc <= length]]
    if len(collar) < 2:
        collar = [tuple(pts[0] * ss), tuple(pts[1] * ss)]
    colour = random_colour(rng)
    sw = wpx * rng.uniform(1.0, 1.6)
    rimmed_stroke(dl, da, collar, colour, colour * rng.uniform(0.3, 0.7), sw)


def rimmed_stroke(dl: ImageDraw.ImageDraw, da: ImageDraw.ImageDraw, pts: list, colour,
                  rim, width: float):
    """A stroke `width` px wide along `pts` on layer `dl`: `rim` at full width with
    `colour` over its middle 70 %, and the full width on alpha `da`."""
    dl.line(pts, fill=tuple(int(v) for v in rim), width=max(1, round(width)))
    dl.line(pts, fill=tuple(int(v) for v in colour), width=max(1, round(width * 0.7)))
    da.line(pts, fill=255, width=max(1, round(width)))


def near_colour(rng: random.Random, colour: np.ndarray) -> np.ndarray:
    """A colour a little off `colour`: brightness within 15 %, each channel within about
    12 levels."""
    jitter = np.array([rng.gauss(0, 12) for _ in range(3)], np.float32)
    return np.clip(colour * rng.uniform(0.85, 1.15) + jitter, 0, 255)


def colour_along(rgb: np.ndarray, path: np.ndarray) -> np.ndarray:
    """The median colour of `rgb` at the points of `path` (clipped to the image)."""
    h, w = rgb.shape[:2]
    xy = np.clip(path.round().astype(int), 0, [w - 1, h - 1])
    return np.median(rgb[xy[:, 1], xy[:, 0]], axis=0)


def abut(path: np.ndarray, width: float, lines: list, rng: random.Random):
    """`path` moved so that its last point lies against one of `lines` at a random
    point in the frame: on it, or beside it by up to 1.5 widths, arriving across it at
    any angle (either end of `path`, at random); None if that line is out of view."""
    h, w = IN_H, IN_W
    other = rng.choice(lines)
    inside = [p for p in other if 8 <= p[0] <= w - 9 and 8 <= p[1] <= h - 9]
    if not inside:
        return None
    anchor = inside[rng.randrange(len(inside))]
    if rng.random() < 0.5:
        path = path[::-1]
    side = np.array([rng.gauss(0, 1), rng.gauss(0, 1)])
    side *= rng.uniform(0, 1.5) * width / (np.linalg.norm(side) + 1e-9)
    return path + (anchor + side - path[-1])


def unit_normals(path: np.ndarray) -> np.ndarray:
    """The unit normal of `path` at each of its points (its tangent turned 90°)."""
    t = np.gradient(path, axis=0)
    n = np.stack([-t[:, 1], t[:, 0]], 1)
    return n / (np.linalg.norm(n, axis=1, keepdims=True) + 1e-9)


def add_cables(scene: Scene, rng: random.Random, count: int, camouflage=False):
    """Draws `count` procedural cables; with `camouflage` the first wears the colour of
    the background it lies on; with chance `ABUTTING` each ends against a cable already
    in the scene."""
    for k in range(count):
        path = random_path(rng)
        colour, width = random_colour(rng), rng.uniform(2.5, 8.0)
        tipped = ()
        if scene.lines and option_drawn(rng, ABUTTING):
            moved = abut(path, width, scene.lines, rng)
            if moved is not None:
                path, tipped = moved, (1,)
        if camouflage and k == 0:
            colour = near_colour(rng, colour_along(scene.rgb, path))
        draw_cable(scene, path, rng, colour, width, tipped=tipped)
        if rng.random() < 0.25:  # a twin of the same colour alongside
            gap = width + rng.uniform(0, 3)
            draw_cable(scene, path + unit_normals(path) * gap, rng,
                       colour * rng.uniform(0.9, 1.1), width)
        if option_drawn(rng, BUNDLES):
            add_bundle(scene, rng, path, colour, width)


def add_bundle(scene: Scene, rng: random.Random, path: np.ndarray, colour, width: float):
    """Draws 2-4 cables of `colour` beside `path`, on one side, each `width` wide and
    0.6-3 widths of gap from the last, their ends staggered; one whose course would
    fold over itself (offset further than the path bends) ends the bundle."""
    n = unit_normals(path) * rng.choice([-1.0, 1.0])
    pitch = width * rng.uniform(1.6, 4.0)
    for k in range(1, rng.randrange(3, 6)):
        line = path + n * pitch * k
        step = np.diff(line, axis=0)
        step /= np.linalg.norm(step, axis=1, keepdims=True) + 1e-9
        if (np.sum(step[1:] * step[:-1], axis=1) < 0.7).any():
            break
        cut = int(rng.uniform(0, 0.15) * len(line))
        line = line[cut:] if rng.random() < 0.5 else line[: len(line) - cut]
        draw_cable(scene, line, rng, colour * rng.uniform(0.9, 1.1), width)


# ---------------------------------------------------------------------------------------
# Composition, augmentation and targets.


def dilate(mask: np.ndarray, radius: int) -> np.ndarray:
    img = Image.fromarray((mask * 255).astype(np.uint8))
    return np.asarray(img.filter(ImageFilter.MaxFilter(2 * radius + 1)), np.float32) / 255


def cable_alpha(p: Photo) -> np.ndarray:
    """Where the photo's cables are, terminals included: the mask, a pixel wider, plus a
    capsule beyond each terminal (the crimped metal lies beyond the insulation)."""
    alpha = Image.fromarray((dilate(p.mask, 1) * 255).astype(np.uint8))
    d = ImageDraw.Draw(alpha)
    for pts in p.lines:
        for end, prev in ((pts[0], pts[min(4, len(pts) - 1)]), (pts[-1], pts[max(-5, -len(pts))])):
            v = end - prev
            v = v / (np.linalg.norm(v) + 1e-9)
            tip = end + v * 10
            d.line((end[0], end[1], tip[0], tip[1]), fill=255, width=6)
    return np.asarray(alpha.filter(ImageFilter.GaussianBlur(0.7)), np.float32) / 255


def hue_rotate(rgb: np.ndarray, angle: float) -> np.ndarray:
    """Rotates colours about the grey axis by `angle` radians."""
    c, s = math.cos(angle), math.sin(angle)
    k = 1 / 3
    sq = math.sqrt(k)
    m = np.array([
        [c + (1 - c) * k, k * (1 - c) - sq * s, k * (1 - c) + sq * s],
        [k * (1 - c) + sq * s, c + k * (1 - c), k * (1 - c) - sq * s],
        [k * (1 - c) - sq * s, k * (1 - c) + sq * s, c + k * (1 - c)],
    ], np.float32)
    return rgb @ m.T


def composite(p: Photo, rng: random.Random) -> Scene:
    """The photo's cables (with their terminals) on a procedural background, optionally
    recoloured."""
    a = cable_alpha(p)[..., None]
    cables = p.rgb
    if rng.random() < 0.5:
        cables = np.clip(hue_rotate(cables, rng.uniform(0, 2 * math.pi)), 0, 255)
    if rng.random() < 0.3:
        cables = np.clip(cables * rng.uniform(0.3, 1.2), 0, 255)
    base = None
    if option_drawn(rng, CAMOUFLAGE):  # the background wears one cable's colour
        base = near_colour(rng, colour_along(cables, rng.choice(p.lines)))
    rgb = cables * a + background(rng, base=base) * (1 - a)
    return Scene(rgb, p.mask.copy(), [l.copy() for l in p.lines], list(p.ends))


def affine(scene: Scene, rng: random.Random) -> Scene:
    """Random rotation, scale, flip and shift of the whole scene."""
    h, w = scene.mask.shape
    angle = rng.uniform(-math.pi, math.pi)
    scale = rng.uniform(0.7, 1.4)
    flip = rng.random() < 0.5
    tx, ty = rng.uniform(-40, 40), rng.uniform(-40, 40)
    cx, cy = w / 2, h / 2
    cos, sin = math.cos(angle) * scale, math.sin(angle) * scale

    def forward(pts):
        pts = np.asarray(pts, np.float64).reshape(-1, 2).copy()
        if flip:
            pts[:, 0] = w - 1 - pts[:, 0]
        dx, dy = pts[:, 0] - cx, pts[:, 1] - cy
        return np.stack([cx + cos * dx - sin * dy + tx, cy + sin * dx + cos * dy + ty], 1)

    det = cos * cos + sin * sin
    ic, is_ = cos / det, -sin / det
    ox, oy = cx + tx, cy + ty
    coeffs = (ic, -is_, cx - ic * ox + is_ * oy, is_, ic, cy - is_ * ox - ic * oy)

    def warp(arr):
        img = Image.fromarray(np.ascontiguousarray(arr, np.float32))
        if flip:
            img = img.transpose(Image.FLIP_LEFT_RIGHT)
        return img.transform((w, h), Image.AFFINE, coeffs, resample=Image.BILINEAR)

    fill = scene.rgb.reshape(-1, 3).mean(0)
    rgb = np.stack([np.asarray(warp(scene.rgb[..., c] - fill[c]), np.float32) + fill[c]
                    for c in range(3)], -1)
    mask = np.asarray(warp(scene.mask), np.float32)
    ends = [tuple(e) for e in forward(scene.ends)] if scene.ends else []
    tol = BORDER_TOLERANCE_PX * INPUT_SCALE
    ends = [(x, y) for x, y in ends if tol <= x <= w - 1 - tol and tol <= y <= h - 1 - tol]
    return Scene(rgb, mask, [forward(l) for l in scene.lines], ends)


def photometric(rgb: np.ndarray, rng: random.Random) -> np.ndarray:
    """Hue rotation, white balance, brightness, contrast, gamma, blur, noise, JPEG."""
    nrng = np.random.default_rng(rng.randrange(1 << 30))
    if rng.random() < 0.5:
        rgb = hue_rotate(rgb, rng.uniform(0, 2 * math.pi))
    if rng.random() < 0.2:
        rgb = rgb[..., rng.sample(range(3), 3)]
    rgb = rgb * np.array([rng.uniform(0.75, 1.25) for _ in range(3)], np.float32)
    mean = rgb.mean()
    rgb = (rgb - mean) * rng.uniform(0.6, 1.4) + mean * rng.uniform(0.6, 1.3)
    rgb = np.clip(rgb, 0, 255)
    if rng.random() < 0.3:
        rgb = 255 * (rgb / 255) ** rng.uniform(0.6, 1.6)
    img = Image.fromarray(rgb.astype(np.uint8))
    if rng.random() < 0.4:
        img = img.filter(ImageFilter.GaussianBlur(rng.uniform(0.2, 1.0)))
    out = np.asarray(img, np.float32)
    if rng.random() < 0.5:
        out = out + nrng.normal(0, rng.uniform(1, 8), out.shape).astype(np.float32)
    out = np.clip(out, 0, 255).astype(np.uint8)
    if rng.random() < 0.5:
        buf = io.BytesIO()
        Image.fromarray(out).save(buf, "JPEG", quality=rng.randrange(30, 95))
        out = np.asarray(Image.open(buf).convert("RGB"))
    return out.astype(np.float32)


def sample_scene(photos: list[Photo], rng: random.Random, real=0.25, composed=0.45,
                 copy_paste=True) -> Scene:
    """One training scene: a real photo (`real`), a photo's cables on a new background
    (`composed`), or procedural cables on a procedural background; with copy-paste off,
    composed scenes become real ones."""
    u = rng.random()
    if u < real or (u < real + composed and not copy_paste):
        scene = photo_scene(rng.choice(photos))
        if rng.random() < 0.3:
            add_cables(scene, rng, rng.randrange(1, 3))
    elif u < real + composed:
        scene = composite(rng.choice(photos), rng)
        if rng.random() < 0.4:
            add_cables(scene, rng, rng.randrange(1, 3))
    else:
        scene = Scene(background(rng), np.zeros((IN_H, IN_W), np.float32))
        hidden = option_drawn(rng, CAMOUFLAGE)  # drawn before the count, as trained
        add_cables(scene, rng, rng.randrange(1, 7), camouflage=hidden)
        scene.rgb = np.clip(scene.rgb, 0, 255)
    scene = affine(scene, rng)
    scene.rgb = photometric(scene.rgb, rng)
    return scene


def targets(scene: Scene, stride=4):
    """Dense targets on the output grid (one cell = `stride` input px): cable
    probability, terminal heatmap with offsets, unsigned orientation (cos 2θ, sin 2θ)
    and where orientation is supervised."""
    h, w = scene.mask.shape
    gh, gw = h // stride, w // stride
    cover = scene.mask[: gh * stride, : gw * stride].reshape(gh, stride, gw, stride).mean((1, 3))
    cable = np.minimum(1.0, 2.0 * cover)
    heat = np.zeros((gh, gw), np.float32)
    offset = np.zeros((2, gh, gw), np.float32)
    end_mask = np.zeros((gh, gw), np.float32)
    ys, xs = np.mgrid[0:gh, 0:gw]
    for x, y in scene.ends:
        gx, gy = x / stride, y / stride
        ix, iy = int(gx), int(gy)
        if not (0 <= ix < gw and 0 <= iy < gh):
            continue
        heat = np.maximum(heat, np.exp(-((xs - ix) ** 2 + (ys - iy) ** 2) / 2.0))
        offset[:, iy, ix] = (gx - ix, gy - iy)
        end_mask[iy, ix] = 1.0
    acc = np.zeros((3, gh, gw), np.float32)
    for pts in scene.lines:
        seg = np.diff(pts, axis=0)
        length = np.linalg.norm(seg, axis=1)
        keep = length > 1e-6
        if not keep.any():
            continue
        a, seg, length = pts[:-1][keep], seg[keep], length[keep]
        n = np.maximum(1, np.ceil(length / 0.5)).astype(int)
        idx = np.repeat(np.arange(len(seg)), n)
        t = np.concatenate([np.arange(k) / k for k in n])
        p = a[idx] + seg[idx] * t[:, None]
        theta = np.arctan2(seg[idx, 1], seg[idx, 0])
        cx, cy = (p[:, 0] / stride).astype(int), (p[:, 1] / stride).astype(int)
        ok = (cx >= 0) & (cx < gw) & (cy >= 0) & (cy < gh)
        np.add.at(acc[0], (cy[ok], cx[ok]), np.cos(2 * theta[ok]))
        np.add.at(acc[1], (cy[ok], cx[ok]), np.sin(2 * theta[ok]))
        np.add.at(acc[2], (cy[ok], cx[ok]), 1.0)
    norm = np.sqrt(acc[0] ** 2 + acc[1] ** 2)
    has = acc[2] > 0
    orient = np.zeros((2, gh, gw), np.float32)
    orient[:, has] = acc[:2, has] / np.maximum(norm[has], 1e-6)
    # Where cables cross, the mean direction is meaningless: supervise only where the
    # samples agree.
    agree = has & (norm / np.maximum(acc[2], 1) > 0.7)
    return cable, heat, offset, end_mask, orient, agree.astype(np.float32)
