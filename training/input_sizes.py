"""The terminal head of the fold networks at other input sizes, on their held-out photos.

Each fold network (`out/field-GROUP.onnx`, `make lobo`) is run on the photos of the
group it never saw, as the service runs it (the photo at half its size, 320x240), and
its terminal peaks decoded as `train_field.decode` does (threshold 0.25, peaks 10 px
apart merged). Two variations, printed as terminal recall / precision (15 px):

- `--union T`: the peaks of a second pass on the photo at a quarter of its size (the
  size the service's probe for wide cables runs at) of at least T are added where no
  peak of the first pass lies within 15 px;
- `--scales S,...`: the photo at another share of its size in place of a half.

    training/.venv/bin/python training/input_sizes.py --union 0.3,0.4,0.5,0.6 --scales 0.75,1
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

import numpy as np
import onnxruntime as ort
from PIL import Image

import scenes
from groups import GROUPS
from train_field import STRIDE, decode, match, to_tensor

NMS_PX = 10.0  # the service's
UNION_PX = 15.0


def field(session, photo: Image.Image, share: float) -> tuple[np.ndarray, float]:
    """The network's output on `photo` resized to `share` of its size (multiples of the
    stride), and the factor from `decode`'s positions (which assume a half-size input)
    to the photo's pixels."""
    w, h = photo.size
    size = (max(STRIDE, round(w * share / STRIDE) * STRIDE),
            max(STRIDE, round(h * share / STRIDE) * STRIDE))
    rgb = np.asarray(photo.resize(size, Image.BILINEAR), np.float32)
    out = session.run(None, {"image": to_tensor(rgb)[None]})[0][0]
    return out, scenes.INPUT_SCALE * w / size[0]


def peaks(session, photo, share, threshold):
    """Terminal peaks (confidence, x, y) in the photo's pixels."""
    out, factor = field(session, photo, share)
    return [(c, x * factor, y * factor) for c, x, y in decode(out, threshold, NMS_PX / factor)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--models", default="out/field-{group}.onnx")
    ap.add_argument("--union", default="", help="thresholds of the quarter-size pass")
    ap.add_argument("--scales", default="", help="input sizes as shares of the photo")
    args = ap.parse_args()
    root = Path(os.environ.get("ARIADNE_DATASET", "../shared/datasets/cables"))
    photos = scenes.load_photos(root)
    rows = [("half (as the service)", 0.5, None)]
    rows += [(f"half + quarter-size peaks >= {t}", 0.5, float(t))
             for t in filter(None, args.union.split(","))]
    rows += [(f"photo at {s}", float(s), None) for s in filter(None, args.scales.split(","))]
    sessions = {g: ort.InferenceSession(args.models.format(group=g)) for g in GROUPS}
    for name, share, union in rows:
        cells = []
        for group in GROUPS:
            tp = found_n = true_n = 0
            for p in (p for p in photos if p.group == group):
                photo = Image.open(root / p.set / f"{p.name}.jpg").convert("RGB")
                found = peaks(sessions[group], photo, share, 0.25)
                if union is not None:
                    for c, x, y in peaks(sessions[group], photo, share / 2, union):
                        if all(math.hypot(x - fx, y - fy) > UNION_PX for _, fx, fy in found):
                            found.append((c, x, y))
                truth = [(x / scenes.INPUT_SCALE, y / scenes.INPUT_SCALE) for x, y in p.ends]
                tp += match(found, truth)
                found_n += len(found)
                true_n += len(truth)
            cells.append(f"{group} {tp / max(true_n, 1):.3f} / {tp / max(found_n, 1):.3f}")
        print(f"{name}: " + ", ".join(cells), flush=True)


if __name__ == "__main__":
    main()
