#!/usr/bin/env python3
"""What `ariadne eval --zoom Z` would score if the engine saw the whole photo: each
`simple/` photo segmented at its own size, its mask cropped to the central 1/Z and
enlarged back as the zoom does, against the truth cropped and enlarged the same way
(weighted IoU of the union masks, the paper's metric, over the cables in view).

    training/.venv/bin/python scripts/zoom_reference.py --binary target/release/ariadne \\
        --zoom 1.5,2,3 --endpoints gt

The gap between this and the zoom rows is what the crop hides from the engine (cables
whose ends lie outside it), not the engine's reading of wider cables. Masks are
resampled bilinearly and thresholded at half, as the evaluation's triangle filter does.
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
from scenes import read_lines, terminals  # noqa: E402

# Ends nearer the border than this are where a cable leaves the frame (the evaluation's
# terminals, `eval::dataset::terminal_ends`).
BORDER_TOLERANCE_PX = 12.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", required=True)
    ap.add_argument("--zoom", default="1.5,2,3")
    ap.add_argument("--endpoints", choices=["gt", "detect"], default="gt")
    ap.add_argument("--dataset", default=os.environ.get("ARIADNE_DATASET", "../shared/datasets/cables"))
    args = ap.parse_args()
    zooms = [float(z) for z in args.zoom.split(",")]
    stems = sorted(p.with_suffix("") for p in (Path(args.dataset) / "simple").glob("*.jpg"))
    sums = {z: [0.0, 0] for z in zooms}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "mask.png"
        for stem in stems:
            w, h = Image.open(f"{stem}.jpg").size
            cmd = [args.binary, "segment", f"{stem}.jpg", "--mask", str(out)]
            if args.endpoints == "gt":
                ends = terminals(read_lines(Path(f"{stem}.txt")), w, h, BORDER_TOLERANCE_PX)
                cmd += ["--endpoints", json.dumps(ends)]
            subprocess.run(cmd, check=True, capture_output=True)
            found = Image.open(out).convert("L")
            truth = Image.open(f"{stem}_mask_all.png").convert("L")
            names = sorted(Path(stem).parent.glob(f"{Path(stem).name}_mask_[0-9]*.png"))
            cables = [Image.open(c).convert("L") for c in names]
            for z in zooms:
                cw, ch = round(w / z), round(h / z)
                box = ((w - cw) // 2, (h - ch) // 2, (w - cw) // 2 + cw, (h - ch) // 2 + ch)

                def view(m):
                    return np.asarray(m.crop(box).resize((w, h), Image.BILINEAR)) > 127

                p, g = view(found), view(truth)
                in_view = sum(view(c).any() for c in cables)
                iou = (p & g).sum() / max(1, (p | g).sum())
                sums[z][0] += in_view * iou
                sums[z][1] += in_view
    for z in zooms:
        print(f"zoom {z:g}  {args.endpoints}  weighted IoU {sums[z][0] / sums[z][1]:.3f}")


if __name__ == "__main__":
    main()
