#!/usr/bin/env python3
"""Writes a copy of the cables dataset as another camera or scene would show it.

Every photo is changed one way; masks and centrelines are copied unchanged. Run the
leave-one-background-out tables on the copy to see what the change costs:

    training/.venv/bin/python scripts/degrade.py blur /tmp/cables-blur
    ARIADNE_DATASET=/tmp/cables-blur python3 scripts/lobo.py --binary target/release/ariadne

Kinds: noise (Gaussian, sigma 10 levels), blur (Gaussian, sigma 1.5 px: a soft lens),
jpeg (quality 25), warm (white balance: red x1.15, blue x0.8), dark (x0.2, gamma 1.5:
a dim cell), invert (a dark background where there was a light one), hue180 (hue
rotated half a turn: other colours of card and cable). Seeded: the same copy every run.
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


KINDS = ["noise", "blur", "jpeg", "warm", "dark", "invert", "hue180"]


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
        if src.suffix == ".jpg":
            image, quality = degrade(Image.open(src).convert("RGB"), args.kind, rng)
            image.save(dst, quality=quality)
        else:
            shutil.copy(src, dst)


if __name__ == "__main__":
    main()
