#!/usr/bin/env python3
"""How far the annotated masks lie from the engine's, per background group.

For every annotated cable of `simple/`, the engine is run with the true ends (the bundled
network's field guiding the walks), the found cable that overlaps the annotated mask most
is taken, and its IoU with that mask is read as drawn and with the found mask shifted by
every whole-pixel offset up to `--reach` px each way. A group whose annotations sit off
the cables in the photo gains much from the best shift, and its best shifts are long;
one the engine misses gains little (a shift does not mend a wrong cable).

    training/.venv/bin/python scripts/annotation_offsets.py [--binary target/release/ariadne]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "training"))
from groups import background_group  # noqa: E402
from scenes import read_lines  # noqa: E402

# Ends this close to the border are where a cable leaves the frame (ariadne eval's rule).
BORDER_TOLERANCE_PX = 12


def shifted_ious(found, truth, reach):
    """IoU of `found` with `truth` for every shift (dx, dy) within `reach` pixels."""
    out = {}
    for dx in range(-reach, reach + 1):
        for dy in range(-reach, reach + 1):
            q = np.roll(np.roll(found, dy, 0), dx, 1)
            out[(dx, dy)] = (q & truth).sum() / max((q | truth).sum(), 1)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", default="target/release/ariadne")
    ap.add_argument("--dataset", default=os.environ.get(
        "ARIADNE_DATASET", str(Path(__file__).resolve().parents[2] / "shared/datasets/cables")))
    ap.add_argument("--reach", type=int, default=3)
    args = ap.parse_args()
    photos = Path(args.dataset) / "simple"
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        labels_png = Path(tmp) / "labels.png"
        for txt in sorted(photos.glob("*.txt")):
            lines = read_lines(txt)
            photo = photos / f"{txt.stem}.jpg"
            width, height = Image.open(photo).size
            ends = [[float(v) for v in e] for line in lines for e in (line[0], line[-1])
                    if min(e[0], e[1], width - 1 - e[0], height - 1 - e[1]) > BORDER_TOLERANCE_PX]
            subprocess.run([args.binary, "segment", str(photo), "--endpoints", json.dumps(ends),
                            "--mask", str(labels_png), "--mask-kind", "labels"],
                           check=True, capture_output=True)
            labels = np.asarray(Image.open(labels_png))
            found_ids = [v for v in np.unique(labels) if v]
            for k in range(len(lines)):
                truth = np.asarray(Image.open(photos / f"{txt.stem}_mask_{k}.png").convert("L")) > 127
                best_id = max(found_ids, key=lambda v: (truth & (labels == v)).sum(), default=None)
                found = labels == best_id if best_id is not None else np.zeros_like(truth)
                ious = shifted_ious(found, truth, args.reach)
                (dx, dy), best = max(ious.items(), key=lambda kv: kv[1])
                group = background_group("simple", txt.stem)
                rows.setdefault(group, []).append((ious[(0, 0)], best, float(np.hypot(dx, dy))))
    print(f"\n| group | cables | IoU as drawn | IoU at the best shift (≤ {args.reach} px) "
          "| mean best shift, px | share shifted ≥ 2 px |")
    print("|---|---|---|---|---|---|")
    for group, r in rows.items():
        r = np.array(r)
        print(f"| {group} | {len(r)} | {r[:, 0].mean():.3f} | {r[:, 1].mean():.3f} "
              f"| {r[:, 2].mean():.2f} | {(r[:, 2] >= 2).mean():.2f} |")


if __name__ == "__main__":
    main()
