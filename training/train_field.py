"""Trains the bundled cable field network and exports it to ONNX.

One forward pass on the photo at half resolution (320x240 for 640x480) predicts, on a
grid of stride 4 (8 photo px per cell), six channels:

    0  cable probability (sigmoid)
    1  terminal probability (sigmoid; CenterNet-style heatmap)
    2  terminal x offset inside the cell, 0..1 (sigmoid)
    3  terminal y offset inside the cell, 0..1 (sigmoid)
    4  cos 2θ of the cable's unsigned direction θ (tanh)
    5  sin 2θ (tanh)

Training scenes (training/scenes.py) mix the development photos, their cables composed
onto procedural backgrounds, and procedurally drawn cables, with heavy photometric
augmentation. Run from the repository root (see models/README.md, the model card):

    python training/train_field.py --out models/cable_field_fp32.onnx              # all photos
    python training/train_field.py --holdout wood --out out/field-wood-fp32.onnx  # one fold

The bundled network's exact recipe is `make train-field` (it adds `--line-textures 0.15`);
`make lobo` trains its folds. The export is the float network; the service runs it
quantized to 8 bits (training/quantize_field.py, which both recipes call).

The network (`--backbone lite0`, the default) is EfficientNet-Lite0's first stages with
ImageNet weights and a small decoder (training/backbone.py); `--backbone none` is the
from-scratch FieldNet below.

With `--holdout GROUP` the photos of that background group (white, wood, blue, hard)
are never trained on and are reported as the fold's validation: the leave-one-
background-out forecast. `--no-copy-paste` and `--no-synthetic` switch ingredients off
to measure what each adds.
"""

from __future__ import annotations

import argparse
import hashlib
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

import scenes
from backbone import LiteFieldNet
from groups import GROUPS

STRIDE = 4
CHANNELS = 6


def conv(cin, cout, stride=1, dilation=1):
    return nn.Sequential(
        nn.Conv2d(cin, cout, 3, stride, padding=dilation, dilation=dilation, bias=False),
        nn.BatchNorm2d(cout),
        nn.ReLU(inplace=True),
    )


class FieldNet(nn.Module):
    """Input [N, 3, H, W] RGB in [0, 1] (H, W multiples of 4); output [N, 6, H/4, W/4]
    (channels in the module docstring)."""

    def __init__(self, width=32):
        super().__init__()
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
        self.head = nn.Conv2d(width, CHANNELS, 1)
        nn.init.constant_(self.head.bias, 0.0)
        with torch.no_grad():
            self.head.bias[0] = -2.0  # most cells are background
            self.head.bias[1] = -4.0  # almost none hold a terminal

    def forward(self, x):
        y = self.head(self.body((x - 0.5) * 4.0))
        return torch.cat([torch.sigmoid(y[:, :4]), torch.tanh(y[:, 4:])], 1)


def focal_loss(pred, heat):
    pred = pred.clamp(1e-4, 1 - 1e-4)
    pos = heat.eq(1).float()
    pos_loss = torch.log(pred) * (1 - pred) ** 2 * pos
    neg_loss = torch.log(1 - pred) * pred**2 * (1 - heat) ** 4 * (1 - pos)
    return -(pos_loss.sum() + neg_loss.sum()) / pos.sum().clamp(min=1)


def losses(out, t, end_weight=1.0):
    cable, heat, offset, end_mask, orient, agree = t
    l_cable = F.binary_cross_entropy(out[:, 0].clamp(1e-4, 1 - 1e-4), cable)
    l_end = focal_loss(out[:, 1], heat)
    l_off = (F.l1_loss(out[:, 2:4], offset, reduction="none") * end_mask[:, None]).sum() \
        / end_mask.sum().clamp(min=1)
    l_orient = (F.l1_loss(out[:, 4:6], orient, reduction="none") * agree[:, None]).sum() \
        / agree.sum().clamp(min=1)
    return 4.0 * l_cable + end_weight * l_end + l_off + l_orient


class SceneStream(torch.utils.data.IterableDataset):
    """Endless training batches, made in a worker process while the model trains.
    Seeded per worker, so a run with the same seed and workers repeats exactly."""

    def __init__(self, photos, args):
        self.photos, self.args = photos, args

    def __iter__(self):
        info = torch.utils.data.get_worker_info()
        rng = scene_rng(self.args, info.id if info else 0)
        while True:
            yield batch(self.photos, rng, self.args.batch, self.args)


def scene_rng(args, worker: int) -> random.Random:
    """The random stream of one scene-making worker."""
    return random.Random(args.seed * 1000 + worker)


def scene_hash(photos, args) -> str:
    """MD5 of the first `args.scene_hash` batches (images and targets) the first worker
    makes: equal hashes mean a checkout makes the scenes a model was trained on."""
    rng, digest = scene_rng(args, 0), hashlib.md5()
    for _ in range(args.scene_hash):
        x, t = batch(photos, rng, args.batch, args)
        for a in [x, *t]:
            digest.update(a.numpy().tobytes())
    return digest.hexdigest()


def to_tensor(rgb: np.ndarray) -> np.ndarray:
    return (rgb.astype(np.float32) / 255.0).transpose(2, 0, 1)


def batch(photos, rng, size, args):
    real, composed = args.real, args.composed
    if args.no_synthetic:  # the same mix without the procedural branch
        real, composed = real / (real + composed), composed / (real + composed)
    xs, ts = [], []
    for _ in range(size):
        s = scenes.sample_scene(photos, rng, real=real, composed=composed,
                                copy_paste=not args.no_copy_paste)
        xs.append(to_tensor(s.rgb))
        ts.append(scenes.targets(s, STRIDE))
    x = torch.from_numpy(np.stack(xs))
    t = [torch.from_numpy(np.stack([tt[i] for tt in ts])) for i in range(6)]
    return x, t


# ---------------------------------------------------------------------------------------
# Evaluation (the Rust decoder in src/detect/output.rs mirrors `decode`).


def decode(out: np.ndarray, threshold=0.35, nms_px=20.0):
    """Terminal peaks of one output, in photo px: cells at or above the threshold that
    are the maximum of their 3x3 neighbourhood, suppressed within `nms_px`."""
    heat = out[1]
    cell = STRIDE / scenes.INPUT_SCALE
    padded = np.pad(heat, 1, constant_values=-1)
    peak = np.ones_like(heat, bool)
    for dy in range(3):
        for dx in range(3):
            peak &= heat >= padded[dy:dy + heat.shape[0], dx:dx + heat.shape[1]]
    cands = np.argwhere((heat >= threshold) & peak)
    scored = sorted(((heat[y, x], (x + out[2, y, x]) * cell, (y + out[3, y, x]) * cell)
                     for y, x in cands), reverse=True)
    kept = []
    for c, x, y in scored:
        if all((x - kx) ** 2 + (y - ky) ** 2 > nms_px**2 for _, kx, ky in kept):
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


def evaluate(model, photos, device="cpu"):
    """Terminal recall / precision (15 px, photo px); the field's cable-cell IoU
    (prediction ≥ 0.5 against target ≥ 0.5 on the grid); centreline coverage (share of
    annotated centreline points whose cell the field calls cable); and the share of
    predicted cable cells more than one cell from any annotated cable."""
    model.eval()
    tp = n_found = n_true = 0
    inter = union = covered = points = stray = positive = 0
    with torch.no_grad():
        for p in photos:
            image = torch.from_numpy(to_tensor(p.rgb))[None].to(device)
            out = model(image)[0].cpu().numpy()
            truth = [(x / scenes.INPUT_SCALE, y / scenes.INPUT_SCALE) for x, y in p.ends]
            found = decode(out)
            tp += match(found, truth)
            n_found += len(found)
            n_true += len(truth)
            scene = scenes.photo_scene(p)
            cable_t = scenes.targets(scene, STRIDE)[0]
            pred = out[0] >= 0.5
            gt = cable_t >= 0.5
            inter += (pred & gt).sum()
            union += (pred | gt).sum()
            near = scenes.dilate((cable_t > 0).astype(np.float32), 1) > 0
            stray += (pred & ~near).sum()
            positive += pred.sum()
            gh, gw = pred.shape
            for line in p.lines:
                for x, y in line:
                    cx, cy = int(x / STRIDE), int(y / STRIDE)
                    if 0 <= cx < gw and 0 <= cy < gh:
                        points += 1
                        covered += bool(pred[cy, cx])
    model.train()
    return {
        "terminal_recall": tp / max(n_true, 1),
        "terminal_precision": tp / max(n_found, 1),
        "cable_iou": float(inter / max(union, 1)),
        "centreline_coverage": covered / max(points, 1),
        "stray_share": float(stray / max(positive, 1)),
        "images": len(photos),
    }


def export_onnx(model: nn.Module, out: Path):
    """Writes `model` as the engine reads it: input `image` [1, 3, H, W], output `field`
    [1, 6, H/4, W/4], any photo size."""
    torch.onnx.export(model, torch.zeros(1, 3, 240, 320), str(out), input_names=["image"],
                      output_names=["field"],
                      dynamic_axes={"image": {2: "height", 3: "width"},
                                    "field": {2: "grid_height", 3: "grid_width"}},
                      opset_version=17, dynamo=False)


# The scene options that are a share or a chance, off (0) by default: each flag, the
# `training/scenes.py` setting it sets, and its help. Off, an option draws no random
# number (`scenes.option_drawn`).
SCENE_SHARES = (
    ("--camouflage", "CAMOUFLAGE",
     "share of composed and procedural scenes where one cable wears the background's colour"),
    ("--sleeves", "SLEEVES",
     "chance that a procedural cable's end wears an insulated sleeve (ferrule or crimp "
     "barrel) of its own colour"),
    ("--line-textures", "LINE_TEXTURES",
     "share of procedural backgrounds drawn with lines that are not cables (masonry, "
     "tiles, handwriting)"),
    ("--abutting", "ABUTTING",
     "chance that a procedural cable drawn after another ends against it"),
    ("--photo-textures", "PHOTO_TEXTURES",
     "share of procedural backgrounds cropped from --background-photos"),
    ("--bundles", "BUNDLES",
     "chance that a procedural cable comes with 2-4 more of its colour laid beside it"),
)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--lr", type=float, default=4e-3)
    ap.add_argument("--width", type=int, default=32, help="channels of the body")
    ap.add_argument("--backbone", choices=["none", "lite0", "lite0-deep"], default="lite0",
                    help="lite0 (the bundled model): EfficientNet-Lite0's first stages, "
                         "ImageNet weights (training/backbone.py); lite0-deep: and its "
                         "stride-16 blocks as context; none: FieldNet from scratch")
    ap.add_argument("--real", type=float, default=0.25, help="share of unmodified photos")
    ap.add_argument("--composed", type=float, default=0.45,
                    help="share of photo cables on procedural backgrounds")
    ap.add_argument("--no-copy-paste", action="store_true")
    ap.add_argument("--no-synthetic", action="store_true")
    ap.add_argument("--rich-textures", action=argparse.BooleanOptionalAction, default=True,
                    help="also mosaic and drip-painting backgrounds (the bundled recipe; "
                         "--no-rich-textures leaves them out)")
    for flag, _, text in SCENE_SHARES:
        ap.add_argument(flag, type=float, default=0.0, help=text)
    ap.add_argument("--background-photos", type=Path,
                    help="folder of photographs for --photo-textures "
                         "(training/fetch_background_photos.sh)")
    ap.add_argument("--holdout", choices=GROUPS)
    ap.add_argument("--end-weight", type=float, default=1.0,
                    help="weight of the terminal heatmap's loss against the rest")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--threads", type=int, default=1, help="PyTorch threads for training")
    ap.add_argument("--workers", type=int, default=1, help="processes making scenes")
    ap.add_argument("--device", default="cpu",
                    help="where the network trains: cpu (the recipe's figures) or cuda")
    ap.add_argument("--out", default="models/cable_field_fp32.onnx")
    ap.add_argument("--scene-hash", type=int, default=0, metavar="N",
                    help="print the MD5 of the first N training batches and stop")
    args = ap.parse_args()

    scenes.RICH_TEXTURES = args.rich_textures
    for flag, name, _ in SCENE_SHARES:
        setattr(scenes, name, getattr(args, flag[2:].replace("-", "_")))
    if args.photo_textures > 0:
        if args.background_photos is None:
            ap.error("--photo-textures needs --background-photos")
        scenes.BACKGROUND_PHOTOS = scenes.load_background_photos(args.background_photos)
    torch.manual_seed(args.seed)
    torch.set_num_threads(args.threads)
    np.random.seed(args.seed)
    root = Path(os.environ.get("ARIADNE_DATASET", "../shared/datasets/cables"))
    photos = scenes.load_photos(root)
    groups = {g: sorted(f"{p.set}/{p.name}" for p in photos if p.group == g)
              for g in GROUPS}
    train = [p for p in photos if p.group != args.holdout]
    held = [p for p in photos if p.group == args.holdout]
    print(f"train {len(train)} photos; held out ({args.holdout}): {len(held)}", flush=True)
    if args.scene_hash:
        print(f"scenes {scene_hash(train, args)}", flush=True)
        return

    if args.backbone.startswith("lite0"):
        model = LiteFieldNet(CHANNELS, args.width, deep=args.backbone == "lite0-deep")
        model.load_pretrained()
        model.freeze_early()
        # the pretrained blocks that train move at a quarter of the new layers' rate
        tuned = [p for n, p in model.named_parameters()
                 if p.requires_grad and n.startswith("_blocks.")]
        fresh = [p for n, p in model.named_parameters()
                 if p.requires_grad and not n.startswith("_blocks.")]
        param_groups, peaks = [{"params": tuned}, {"params": fresh}], [args.lr / 4, args.lr]
    else:
        model = FieldNet(args.width)
        param_groups, peaks = [{"params": list(model.parameters())}], [args.lr]
    n_params = sum(p.numel() for p in model.parameters())
    model.to(args.device)
    opt = torch.optim.AdamW(param_groups, lr=args.lr, weight_decay=1e-4)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=peaks, total_steps=args.steps)
    history, start, window = [], time.time(), []
    stream = iter(torch.utils.data.DataLoader(
        SceneStream(train, args), batch_size=None, num_workers=args.workers))
    for step in range(1, args.steps + 1):
        x, t = next(stream)
        x, t = x.to(args.device), [a.to(args.device) for a in t]
        loss = losses(model(x), t, args.end_weight)
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
        window.append(loss.item())
        if step % 250 == 0 or step == args.steps:
            entry = {"step": step, "loss": float(np.mean(window)),
                     "seconds": round(time.time() - start)}
            if held:
                entry["held_out"] = evaluate(model, held, args.device)
            history.append(entry)
            window = []
            print(json.dumps(entry), flush=True)

    model.eval()
    report = {"args": vars(args), "parameters": n_params, "groups": groups,
              "history": history, "train": evaluate(model, train, args.device),
              "held_out": evaluate(model, held, args.device) if held else None,
              "train_seconds": round(time.time() - start)}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    model.cpu()
    export_onnx(model, out)
    torch.save(model.state_dict(), out.with_suffix(".pt"))
    out.with_suffix(".train.json").write_text(json.dumps(report, indent=2, default=str) + "\n")
    print(json.dumps({"train": report["train"], "held_out": report["held_out"]}), flush=True)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
