#!/usr/bin/env python3
"""Writes a copy of the cables dataset as another camera or scene would show it.

Every photo is changed one way; masks and centrelines are copied unchanged (but by
`portrait`, which turns them with the photo). Run the
leave-one-background-out tables on the copy to see what the change costs:

    training/.venv/bin/python scripts/degrade.py blur /tmp/cables-blur
    ARIADNE_DATASET=/tmp/cables-blur python3 scripts/lobo.py --binary target/release/ariadne

Kinds: noise (Gaussian, sigma 10 levels), blur (Gaussian, sigma 1.5 px: a soft lens),
jpeg (quality 25), warm (white balance: red x1.15, blue x0.8), dark (x0.2, gamma 1.5:
a dim cell), invert (a dark background where there was a light one), hue180 (hue
rotated half a turn: other colours of card and cable), portrait (photo, masks and
centrelines turned a quarter turn clockwise: a camera held upright; 640x480 becomes
480x640). Seeded: the same copy every run.
"""

import argparse
import os
import shutil
from pathlib import Path

import numpy as np
from PIL import Image, ImageFilter


def degrade(image, kind, rng):
    """The photo `image` (RGB) changed as `kind` says, and the JPEG quality to save it at."""
    a = np.asarray(image).astype(np.float64)
    if kind == "noise":
        a = a + rng.normal(0.0, 10.0, a.shape)
    elif kind == "blur":
        return image.filter(ImageFilter.GaussianBlur(1.5)), 92
    elif kind == "jpeg":
        return image, 25
    elif kind == "warm":
        a = a * [1.15, 1.0, 0.8]
    elif kind == "dark":
        a = 255.0 * (0.2 * (a / 255.0) ** 1.5)
    elif kind == "invert":
        a = 255.0 - a
    elif kind == "hue180":
        hsv = np.array(image.convert("HSV"))
        hsv[..., 0] = (hsv[..., 0].astype(int) + 128) % 256
        return Image.fromarray(hsv, "HSV").convert("RGB"), 92
    else:
        raise ValueError(f"unknown kind {kind}")
    return Image.fromarray(a.clip(0, 255).astype(np.uint8)), 92


KINDS = ["noise", "blur", "jpeg", "warm", "dark", "invert", "hue180", "portrait"]


def turned(points, height):
    """Centreline points `[x0, y0, x1, y1, ...]` of a photo `height` pixels high, turned
    a quarter turn clockwise with it: (x, y) becomes (height - 1 - y, x)."""
    out = []
    for x, y in zip(points[::2], points[1::2]):
        out += [height - 1 - y, x]
    return out


def copy_turned(src, dst):
    """A photo, mask or centreline file of the dataset turned a quarter turn clockwise.

    The hand-drawn masks lie half a pixel up and left of their centrelines (the
    convention of the tool that drew them, which the engine's masks follow:
    `render::MASK_PIXEL_CENTRE`). Turned, that offset would point up and right, a
    mismatch that cost `simple` 0.035 of weighted IoU with the true ends (0.704 against
    0.739) with no change in the photo, so a turned mask is moved one pixel left to keep
    the convention. (On a half turn: 0.643 with the masks only turned, 0.738 with them
    also moved one pixel up and left, 0.733 on the photos as they are, re-encoded
    alike.)"""
    if src.suffix == ".jpg":
        Image.open(src).transpose(Image.Transpose.ROTATE_270).save(dst, quality=95)
    elif src.suffix == ".png":
        turned_mask = np.asarray(Image.open(src).transpose(Image.Transpose.ROTATE_270))
        moved = np.zeros_like(turned_mask)
        moved[:, :-1] = turned_mask[:, 1:]
        Image.fromarray(moved).save(dst)
    elif src.suffix == ".txt":
        height = Image.open(src.with_suffix(".jpg")).height
        lines = []
        for line in src.read_text().splitlines():
            values = line.split()
            if not values:
                continue
            points = turned([float(v) for v in values[1:]], height)
            lines.append(" ".join([values[0]] + [f"{v:g}" for v in points]))
        dst.write_text("\n".join(lines) + "\n")
    else:
        shutil.copy(src, dst)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("kind", choices=KINDS)
    ap.add_argument("out", type=Path)
    ap.add_argument("--dataset", type=Path,
                    default=Path(os.environ.get("ARIADNE_DATASET", "../shared/datasets/cables")))
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    for src in sorted(args.dataset.rglob("*")):
        dst = args.out / src.relative_to(args.dataset)
        if src.is_dir():
            continue
        dst.parent.mkdir(parents=True, exist_ok=True)
        if args.kind == "portrait":
            copy_turned(src, dst)
        elif src.suffix == ".jpg":
            image, quality = degrade(Image.open(src).convert("RGB"), args.kind, rng)
            image.save(dst, quality=quality)
        else:
            shutil.copy(src, dst)


if __name__ == "__main__":
    main()
