#!/usr/bin/env python3
"""Leave-one-background-out figures from `ariadne eval --json` runs.

For each background group (white, wood, blue: simple/ by photo number; hard: hard/),
runs `ariadne eval` with the model trained without that group (out/field-GROUP.onnx:
training/train_field.py --holdout GROUP, quantized as the bundled one, by `make lobo`)
and reports, on that group's photos only: weighted IoU (the paper's metric), cable
recall, terminal recall and precision; with the network's ends, also what lies near the
missed terminals (an end found a little too far away, the image border, nothing) and
near the false ends (a terminal a little too far away, the border, an annotated cable,
none of them).

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
        "terminal_recall_on_cables": sum(i["terminals_matched_on_cables"] for i in images)
        / max(sum(i["terminals"] for i in images), 1),
        "terminal_precision_on_cables": sum(i["terminals_matched_on_cables"] for i in images)
        / max(sum(i["ends_on_cables"] for i in images), 1),
        "terminals": sum(i["terminals"] for i in images),
        "misses": miss_kinds([m for i in images for m in i["missed_terminals"]]),
        "ends": sum(i["ends"] for i in images),
        "false": false_kinds([e for i in images for e in i["false_ends"]]),
    }


# A missed terminal with an end this near (or a false end with a terminal this near)
# was marked elsewhere on the same terminal (metal tip against insulation end); one
# this near the border, with nothing near, is likely an annotated end short of the
# frame where the cable leaves it; a false end this near an annotated cable's mask lies
# on that cable.
TERMINAL_MATCH_PX = 15.0  # ariadne eval's matching radius
NEAR_END_PX = 30.0
NEAR_FRAME_PX = 20.0
ON_CABLE_PX = 10.0


def false_kinds(ends):
    kinds = {"all": len(ends), "terminal_near": 0, "at_frame": 0, "on_cable": 0, "off_cables": 0}
    for e in ends:
        if (e["nearest_terminal_px"] or 1e9) <= NEAR_END_PX:
            kinds["terminal_near"] += 1
        elif e["border_px"] <= NEAR_FRAME_PX:
            kinds["at_frame"] += 1
        elif (e["nearest_cable_px"] or 1e9) <= ON_CABLE_PX:
            kinds["on_cable"] += 1
        else:
            kinds["off_cables"] += 1
    return kinds


def miss_kinds(missed):
    near = [m for m in missed if (m["nearest_end_px"] or 1e9) <= NEAR_END_PX]
    frame = [m for m in missed if m not in near and m["border_px"] <= NEAR_FRAME_PX]
    return {"all": len(missed), "end_near": len(near), "at_frame": len(frame),
            "elsewhere": len(missed) - len(near) - len(frame)}


def table(headers, rows):
    """Prints a Markdown table after a blank line."""
    print()
    print("| " + " | ".join(headers) + " |")
    print("|" + "---|" * len(headers))
    for row in rows:
        print("| " + " | ".join(str(c) for c in row) + " |")


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
    table(["held-out group", "images", "weighted IoU", "cable recall", "terminal recall",
           "terminal precision"],
          [[g, r["images"], f"{r['weighted_iou']:.3f}", f"{r['cable_recall']:.3f}",
            f"{r['terminal_recall']:.3f}", f"{r['terminal_precision']:.3f}"]
           for g, r in rows.items()])
    if args.endpoints == "detect":
        table(["held-out group", "terminal recall, ends on a cable",
               "terminal precision, ends on a cable"],
              [[g, f"{r['terminal_recall_on_cables']:.3f}",
                f"{r['terminal_precision_on_cables']:.3f}"] for g, r in rows.items()])
        table(["held-out group", "terminals", "missed",
               f"an end {TERMINAL_MATCH_PX:g}-{NEAR_END_PX:g} px away",
               f"within {NEAR_FRAME_PX:g} px of the border, no end near", "elsewhere"],
              [[g, r["terminals"], m["all"], m["end_near"], m["at_frame"], m["elsewhere"]]
               for g, r in rows.items() for m in [r["misses"]]])
        table(["held-out group", "ends", "false",
               f"a terminal {TERMINAL_MATCH_PX:g}-{NEAR_END_PX:g} px away",
               f"within {NEAR_FRAME_PX:g} px of the border",
               f"on an annotated cable (≤ {ON_CABLE_PX:g} px)", "off the annotated cables"],
              [[g, r["ends"], f["all"], f["terminal_near"], f["at_frame"], f["on_cable"],
                f["off_cables"]] for g, r in rows.items() for f in [r["false"]]])
    json.dump(rows, sys.stderr)


if __name__ == "__main__":
    main()
