#!/usr/bin/env python3
"""Leave-one-background-out figures from `ariadne eval --json` runs.

For each background group (white, wood, blue: simple/ by photo number; hard: hard/),
runs `ariadne eval` with the model trained without that group (out/field-GROUP.onnx,
made by training/train_field.py --holdout GROUP) and reports, on that group's photos
only: weighted IoU (the paper's metric), cable recall, terminal recall and precision.

    python3 scripts/lobo.py [--endpoints detect|gt] [--binary target/release/ariadne]
"""

import argparse
import json
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "training"))
from groups import GROUPS, background_group  # noqa: E402


def group_of(image):
    return background_group(image["set"], image["name"])


def summarise(images):
    cables = sum(i["gt_cables"] for i in images)
    return {
        "images": len(images),
        "weighted_iou": sum(i["iou"] * i["gt_cables"] for i in images) / max(cables, 1),
        "cable_recall": sum(i["matched_cables"] for i in images) / max(cables, 1),
        "terminal_recall": sum(i["terminals_matched"] for i in images)
        / max(sum(i["terminals"] for i in images), 1),
        "terminal_precision": sum(i["terminals_matched"] for i in images)
        / max(sum(i["ends"] for i in images), 1),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--endpoints", default="detect", choices=["detect", "gt"])
    ap.add_argument("--binary", default="target/release/ariadne")
    ap.add_argument("--models", default="out/field-{group}.onnx")
    ap.add_argument("--options", default=None)
    ap.add_argument("--exposure", default="1", help="ariadne eval --exposure (darker photos)")
    ap.add_argument("--groups", default=",".join(GROUPS), help="comma-separated subset")
    args = ap.parse_args()
    rows = {}
    for group in args.groups.split(","):
        cmd = [args.binary, "eval", "--json", "--endpoints", args.endpoints,
               "--model", args.models.format(group=group), "--exposure", args.exposure]
        if args.options:
            cmd += ["--options", args.options]
        doc = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
        rows[group] = summarise([i for i in doc["images"] if group_of(i) == group])
    print(f"ends: {args.endpoints}")
    print("| held-out group | images | weighted IoU | cable recall | terminal recall | terminal precision |")
    print("|---|---|---|---|---|---|")
    for g, r in rows.items():
        print(f"| {g} | {r['images']} | {r['weighted_iou']:.3f} | {r['cable_recall']:.3f} "
              f"| {r['terminal_recall']:.3f} | {r['terminal_precision']:.3f} |")
    json.dump(rows, sys.stderr)


if __name__ == "__main__":
    main()
