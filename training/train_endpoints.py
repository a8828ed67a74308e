"""Trains the bundled cable-end detector and exports it to ONNX.

A small fully convolutional keypoint network (CenterNet-style): it sees the photo at
half resolution (320x240 for a 640x480 image) and predicts, on a grid of stride 4
(8 px in the original), the probability that a cable end lies in each cell and the end's
sub-cell offset. Targets are the terminal ends of the development split's centrelines
(first and last points, except those on the image border); training adds geometric and
photometric augmentation and synthetic cable scenes.

Run from the repository root (see models/README.md):

    python training/train_endpoints.py --out models/endpoints.onnx

The validation images are fixed (VALIDATION below) and never used for training.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import time
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F
from PIL import Image, ImageDraw, ImageFilter

# Same tolerance as the Rust evaluator (src/eval/dataset.rs): ends this close to the
# border are where a cable leaves the frame, not terminals.
BORDER_TOLERANCE_PX = 12.0
STRIDE = 4
INPUT_SCALE = 0.5  # the network sees the photo at half resolution
# Held out from training: every fifth simple image and the last hard one.
VALIDATION = {("simple", f"{i:05d}") for i in range(4, 40, 5)} | {("hard", "00002")}


def dataset_dir() -> Path:
    return Path(os.environ.get("ARIADNE_DATASET", "../shared/datasets/cables"))


def terminal_ends(txt: Path, width: int, height: int) -> list[tuple[float, float]]:
    ends = []
    for line in txt.read_text().splitlines():
        values = line.split()
        if not values:
            continue
        k = int(values[0])
        pts = [(float(values[1 + 2 * i]), float(values[2 + 2 * i])) for i in range(k)]
        for x, y in (pts[0], pts[-1]):
            on_border = (
                x < BORDER_TOLERANCE_PX
                or y < BORDER_TOLERANCE_PX
                or x > width - 1 - BORDER_TOLERANCE_PX
                or y > height - 1 - BORDER_TOLERANCE_PX
            )
            if not on_border:
                ends.append((x, y))
    return ends


def load_split(root: Path):
    train, val = [], []
    for set_name in ("simple", "hard"):
        for jpg in sorted((root / set_name).glob("*.jpg")):
            image = Image.open(jpg).convert("RGB")
            ends = terminal_ends(jpg.with_suffix(".txt"), *image.size)
            sample = (set_name, jpg.stem, image, ends)
            (val if (set_name, jpg.stem) in VALIDATION else train).append(sample)
    return train, val


# ---------------------------------------------------------------------------------------
# Synthetic scenes: smooth cables with terminals on plain or textured backgrounds.


def random_colour(rng: random.Random) -> tuple[int, int, int]:
    return tuple(rng.randrange(256) for _ in range(3))


def bezier(points, n=200):
    p0, p1, p2, p3 = (np.array(p, dtype=np.float64) for p in points)
    t = np.linspace(0.0, 1.0, n)[:, None]
    return (1 - t) ** 3 * p0 + 3 * (1 - t) ** 2 * t * p1 + 3 * (1 - t) * t**2 * p2 + t**3 * p3


def synthetic_scene(rng: random.Random, width=640, height=480):
    base = random_colour(rng) if rng.random() < 0.5 else (rng.randrange(150, 256),) * 3
    image = Image.new("RGB", (width, height), base)
    draw = ImageDraw.Draw(image)
    if rng.random() < 0.5:  # texture: random strokes and blobs
        for _ in range(rng.randrange(20, 120)):
            x, y = rng.randrange(width), rng.randrange(height)
            r = rng.randrange(3, 40)
            if rng.random() < 0.5:
                draw.ellipse((x - r, y - r, x + r, y + r), fill=random_colour(rng))
            else:
                draw.line((x, y, x + rng.randint(-80, 80), y + rng.randint(-80, 80)),
                          fill=random_colour(rng), width=rng.randrange(1, 6))
    ends = []
    for _ in range(rng.randrange(2, 9)):
        margin = 60
        ctrl = [(rng.uniform(-margin, width + margin), rng.uniform(-margin, height + margin))
                for _ in range(4)]
        curve = bezier(ctrl)
        thickness = rng.randrange(6, 14)
        colour = random_colour(rng)
        shade = tuple(int(c * 0.6) for c in colour)
        pts = [tuple(p) for p in curve]
        draw.line(pts, fill=shade, width=thickness + 2, joint="curve")
        draw.line(pts, fill=colour, width=thickness, joint="curve")
        for end, prev in ((curve[0], curve[5]), (curve[-1], curve[-6])):
            x, y = end
            if not (BORDER_TOLERANCE_PX < x < width - 1 - BORDER_TOLERANCE_PX
                    and BORDER_TOLERANCE_PX < y < height - 1 - BORDER_TOLERANCE_PX):
                continue
            ends.append((float(x), float(y)))
            if rng.random() < 0.8:  # a crimped metal terminal beyond the insulation
                d = end - prev
                d = d / (np.linalg.norm(d) + 1e-9)
                length = rng.uniform(10, 30)
                tip = end + d * length
                metal = (rng.randrange(120, 230),) * 3
                draw.line((x, y, tip[0], tip[1]), fill=metal, width=max(3, thickness - 3))
    image = image.filter(ImageFilter.GaussianBlur(rng.uniform(0.3, 1.2)))
    return image, ends


# ---------------------------------------------------------------------------------------
# Augmentation and targets.


def augment(image: Image.Image, ends, rng: random.Random):
    """Random rotation, scale, flip and shift of the photo (and its ends), then colour."""
    w, h = image.size
    angle = rng.uniform(-180, 180)
    scale = rng.uniform(0.8, 1.25)
    flip = rng.random() < 0.5
    tx, ty = rng.uniform(-60, 60), rng.uniform(-60, 60)
    cx, cy = w / 2, h / 2
    a = math.radians(angle)
    cos, sin = math.cos(a) * scale, math.sin(a) * scale

    def forward(x, y):
        if flip:
            x = w - 1 - x
        dx, dy = x - cx, y - cy
        return cx + cos * dx - sin * dy + tx, cy + sin * dx + cos * dy + ty

    # PIL wants the inverse map (output -> input), as an affine 6-tuple.
    det = cos * cos + sin * sin
    ic, is_ = cos / det, -sin / det
    ox, oy = cx + tx, cy + ty
    coeffs = (ic, -is_, cx - ic * ox + is_ * oy, is_, ic, cy - is_ * ox - ic * oy)
    src = image.transpose(Image.FLIP_LEFT_RIGHT) if flip else image
    fill = tuple(int(v) for v in np.asarray(image).reshape(-1, 3).mean(0))
    out = src.transform((w, h), Image.AFFINE, coeffs, resample=Image.BILINEAR, fillcolor=fill)
    moved = [forward(x, y) for x, y in ends]
    moved = [(x, y) for x, y in moved if 0 <= x < w and 0 <= y < h]

    arr = np.asarray(out).astype(np.float32)
    # Colour: per-channel gain, brightness, contrast, channel permutation, noise.
    if rng.random() < 0.5:
        arr = arr[:, :, rng.sample(range(3), 3)]
    arr = arr * np.array([rng.uniform(0.85, 1.15) for _ in range(3)], np.float32)
    mean = arr.mean()
    arr = (arr - mean) * rng.uniform(0.7, 1.3) + mean + rng.uniform(-30, 30)
    arr = arr + np.random.default_rng(rng.randrange(1 << 30)).normal(0, rng.uniform(0, 6), arr.shape)
    return np.clip(arr, 0, 255).astype(np.uint8), moved


def to_input(arr: np.ndarray) -> np.ndarray:
    """HxWx3 uint8 photo -> 3 x H/2 x W/2 float in [0, 1], as the Rust side feeds it."""
    image = Image.fromarray(arr)
    w, h = image.size
    small = image.resize((int(w * INPUT_SCALE), int(h * INPUT_SCALE)), Image.BILINEAR)
    return np.asarray(small, np.float32).transpose(2, 0, 1) / 255.0


def targets(ends, in_h: int, in_w: int, sigma_cells=1.0):
    gh, gw = in_h // STRIDE, in_w // STRIDE
    heat = np.zeros((gh, gw), np.float32)
    offset = np.zeros((2, gh, gw), np.float32)
    mask = np.zeros((gh, gw), np.float32)
    ys, xs = np.mgrid[0:gh, 0:gw]
    cell = STRIDE / INPUT_SCALE
    for x, y in ends:
        gx, gy = x / cell, y / cell
        ix, iy = int(gx), int(gy)
        if not (0 <= ix < gw and 0 <= iy < gh):
            continue
        g = np.exp(-((xs - ix) ** 2 + (ys - iy) ** 2) / (2 * sigma_cells**2))
        heat = np.maximum(heat, g)
        offset[:, iy, ix] = (gx - ix, gy - iy)
        mask[iy, ix] = 1.0
    return heat, offset, mask


# ---------------------------------------------------------------------------------------
# Network.


def conv(cin, cout, stride=1, dilation=1):
    return nn.Sequential(
        nn.Conv2d(cin, cout, 3, stride, padding=dilation, dilation=dilation, bias=False),
        nn.BatchNorm2d(cout),
        nn.ReLU(inplace=True),
    )


class EndNet(nn.Module):
    """Input [N, 3, H, W] in [0, 1] (H, W multiples of 4); output [N, 3, H/4, W/4]:
    end probability, then x and y offsets within the cell in [0, 1]."""

    def __init__(self, width=24):
        super().__init__()
        self.register_buffer("mean", torch.tensor([0.5, 0.5, 0.5]).view(1, 3, 1, 1))
        self.body = nn.Sequential(
            conv(3, 16, stride=2),
            conv(16, 16),
            conv(16, width, stride=2),
            conv(width, width),
            conv(width, width, dilation=2),
            conv(width, width, dilation=4),
            conv(width, width, dilation=8),
            conv(width, width),
        )
        self.head = nn.Conv2d(width, 3, 1)
        nn.init.constant_(self.head.bias, 0.0)
        with torch.no_grad():
            self.head.bias[0] = -4.0  # start near "no end anywhere"

    def forward(self, x):
        y = self.head(self.body((x - self.mean) * 4.0))
        return torch.sigmoid(y)


def focal_loss(pred, heat):
    pred = pred.clamp(1e-4, 1 - 1e-4)
    pos = heat.eq(1).float()
    neg = 1 - pos
    pos_loss = torch.log(pred) * (1 - pred) ** 2 * pos
    neg_loss = torch.log(1 - pred) * pred**2 * (1 - heat) ** 4 * neg
    n = pos.sum().clamp(min=1)
    return -(pos_loss.sum() + neg_loss.sum()) / n


# ---------------------------------------------------------------------------------------
# Decoding and evaluation (the Rust decoder in src/detect mirrors this).


def decode(out: np.ndarray, threshold=0.3, nms_radius_px=12.0):
    heat, ox, oy = out
    cell = STRIDE / INPUT_SCALE
    cands = np.argwhere(heat >= threshold)
    scored = sorted(((heat[y, x], (x + ox[y, x]) * cell, (y + oy[y, x]) * cell)
                     for y, x in cands), reverse=True)
    kept = []
    for c, x, y in scored:
        if all((x - kx) ** 2 + (y - ky) ** 2 > nms_radius_px**2 for _, kx, ky in kept):
            kept.append((c, x, y))
    return kept


def match(found, truth, radius=15.0):
    used, tp = set(), 0
    for _, x, y in found:
        best = None
        for j, (tx, ty) in enumerate(truth):
            d = math.hypot(x - tx, y - ty)
            if j not in used and d <= radius and (best is None or d < best[0]):
                best = (d, j)
        if best:
            used.add(best[1])
            tp += 1
    return tp


def evaluate(model, samples, threshold=0.3):
    model.eval()
    tp = n_found = n_true = 0
    with torch.no_grad():
        for _, _, image, ends in samples:
            x = torch.from_numpy(to_input(np.asarray(image)))[None]
            found = decode(model(x)[0].numpy(), threshold)
            tp += match(found, ends)
            n_found += len(found)
            n_true += len(ends)
    model.train()
    return tp / max(n_true, 1), tp / max(n_found, 1)


def batch(samples, rng, size, synthetic_fraction):
    xs, heats, offs, masks = [], [], [], []
    for _ in range(size):
        if rng.random() < synthetic_fraction:
            image, ends = synthetic_scene(rng)
        else:
            _, _, image, ends = rng.choice(samples)
        arr, ends = augment(image, ends, rng)
        x = to_input(arr)
        heat, off, mask = targets(ends, x.shape[1], x.shape[2])
        xs.append(x)
        heats.append(heat)
        offs.append(off)
        masks.append(mask)
    return (torch.from_numpy(np.stack(xs)), torch.from_numpy(np.stack(heats)),
            torch.from_numpy(np.stack(offs)), torch.from_numpy(np.stack(masks)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--epochs", type=int, default=350)
    ap.add_argument("--steps-per-epoch", type=int, default=12)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--lr", type=float, default=3e-3)
    ap.add_argument("--synthetic", type=float, default=0.2)
    ap.add_argument("--width", type=int, default=32, help="channels of the body")
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--out", default="models/endpoints.onnx")
    args = ap.parse_args()

    torch.manual_seed(args.seed)
    rng = random.Random(args.seed)
    train, val = load_split(dataset_dir())
    print(f"train {len(train)} images, validation {len(val)}: "
          f"{sorted(f'{s}/{n}' for s, n, _, _ in val)}")
    model = EndNet(args.width)
    opt = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    total = args.epochs * args.steps_per_epoch
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=args.lr, total_steps=total)
    history = []
    start = time.time()
    for epoch in range(args.epochs):
        losses = []
        for _ in range(args.steps_per_epoch):
            x, heat, off, mask = batch(train, rng, args.batch, args.synthetic)
            out = model(x)
            l_heat = focal_loss(out[:, 0], heat)
            l_off = (F.l1_loss(out[:, 1:], off, reduction="none") * mask[:, None]).sum() / mask.sum().clamp(min=1)
            loss = l_heat + l_off
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            losses.append(loss.item())
        if epoch % 10 == 9 or epoch == args.epochs - 1:
            recall, precision = evaluate(model, val)
            history.append({"epoch": epoch + 1, "loss": float(np.mean(losses)),
                            "val_recall": recall, "val_precision": precision})
            print(f"epoch {epoch + 1:4d} loss {np.mean(losses):.3f} "
                  f"val recall {recall:.3f} precision {precision:.3f} "
                  f"({time.time() - start:.0f} s)", flush=True)

    model.eval()
    train_r, train_p = evaluate(model, train)
    val_r, val_p = evaluate(model, val)
    print(f"final: train recall {train_r:.3f} precision {train_p:.3f}; "
          f"validation recall {val_r:.3f} precision {val_p:.3f}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    dummy = torch.zeros(1, 3, 240, 320)
    torch.onnx.export(model, dummy, str(out), input_names=["image"], output_names=["heatmap"],
                      dynamic_axes={"image": {2: "height", 3: "width"},
                                    "heatmap": {2: "grid_height", 3: "grid_width"}},
                      opset_version=17, dynamo=False)
    report = {"args": vars(args), "history": history,
              "train": {"recall": train_r, "precision": train_p},
              "validation": {"recall": val_r, "precision": val_p},
              "validation_images": sorted(f"{s}/{n}" for s, n in VALIDATION)}
    torch.save(model.state_dict(), out.with_suffix(".pt"))
    out.with_suffix(".train.json").write_text(json.dumps(report, indent=2) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
