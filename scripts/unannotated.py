#!/usr/bin/env python3
"""Found cables that lie off every annotated cable, and what they cost the weighted IoU.

Every photo of the development split is segmented from the photo alone (the bundled
network; `clutter` for `hard/`, as `ariadne eval` does), with the service's label mask
(`--mask-kind labels`: each cable's own mask, as `ariadne eval` draws them), and the
share of each cable's mask on the annotated union mask is read. A cable with almost
none of it there (under `--share`) is either a false cable or a cable the annotation
leaves out: look at the listed ones. The weighted IoU is then read with all the found
cables and without those.

    training/.venv/bin/python scripts/unannotated.py [--binary target/release/ariadne]
"""

import argparse
import json
import os
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", default="target/release/ariadne")
    ap.add_argument("--share", type=float, default=0.05,
                    help="a cable with less of its stroke on the annotation is listed")
    args = ap.parse_args()
    root = Path(os.environ.get("ARIADNE_DATASET", "../shared/datasets/cables"))
    for set_name, preset in (("simple", "default"), ("hard", "clutter")):
        weighted_all = weighted_kept = cables_total = 0.0
        found = listed = 0
        for jpg in sorted((root / set_name).glob("*.jpg")):
            with tempfile.TemporaryDirectory() as tmp:
                out, labels_png = Path(tmp) / "r.json", Path(tmp) / "labels.png"
                subprocess.run([args.binary, "segment", str(jpg), "--preset", preset,
                                "--json", str(out), "--mask", str(labels_png),
                                "--mask-kind", "labels"], check=True, capture_output=True)
                result = json.loads(out.read_text())
                labels = np.asarray(Image.open(labels_png))
            truth = np.asarray(Image.open(jpg.with_name(f"{jpg.stem}_mask_all.png"))
                               .convert("L")) > 127
            every = np.zeros_like(truth)
            kept = np.zeros_like(truth)
            for cable in result["cables"]:
                mask = labels == cable["id"] + 1
                share = (mask & truth).sum() / max(mask.sum(), 1)
                every |= mask
                found += 1
                if share < args.share:
                    listed += 1
                    ends = [[round(v) for v in p] for p in cable["endpoints"]]
                    print(f"{set_name}/{jpg.stem} cable {cable['id']}: {share:.2f} on the "
                          f"annotation, {cable['length_px']:.0f} px, score "
                          f"{cable['score']:.3f}, ends {ends}")
                else:
                    kept |= mask
            count = sum(1 for line in jpg.with_suffix(".txt").read_text().splitlines()
                        if line.strip())
            weighted_all += count * (every & truth).sum() / max((every | truth).sum(), 1)
            weighted_kept += count * (kept & truth).sum() / max((kept | truth).sum(), 1)
            cables_total += count
        print(f"{set_name}: {listed} of {found} found cables listed; weighted IoU "
              f"{weighted_all / cables_total:.4f} with them, "
              f"{weighted_kept / cables_total:.4f} without")


if __name__ == "__main__":
    main()
