#!/usr/bin/env python3
"""Where the reported ends lie along their cables, against the annotated ends.

For every annotated terminal (a centreline end at least 12 px from the border, as
`ariadne eval` counts them), the nearest end `ariadne segment` reports within 30 px is
read as a signed distance along the annotated cable: positive when the reported end lies
inward, on the cable, negative when it lies beyond the annotated end (on the metal).
Then terminal recall (15 px, one to one, the most confident ends first, as `ariadne
eval` pairs them) with every end a cable was assigned to moved along that cable's
polyline by each of `--shifts` pixels (positive: inward). Per background group on the
development split (each group with its own model when `--model` names `{group}`, the
leave-one-background-out folds by default), per set on any other dataset.

    training/.venv/bin/python scripts/end_offsets.py [--binary target/release/ariadne]
        [--model 'out/field-{group}.onnx'] [--dataset DIR] [--shifts -6,-3,0,3,6]
"""

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "training"))
from groups import background_group  # noqa: E402
from scenes import BORDER_TOLERANCE_PX, read_lines  # noqa: E402

TERMINAL_MATCH_PX = 15.0  # ariadne eval's matching radius
NEAR_PX = 30.0  # a reported end this near a terminal is read as marking it
DIRECTION_PX = 15.0  # centreline length read back from an end for the cable's direction


def inward(line, end_index, reach=DIRECTION_PX):
    """Unit vector from the end `end_index` (0 or -1) of polyline `line` into the cable,
    towards the point `reach` pixels along it."""
    seq = line if end_index == 0 else line[::-1]
    walked, point = 0.0, seq[0]
    for a, b in zip(seq, seq[1:]):
        walked += math.dist(a, b)
        point = b
        if walked >= reach:
            break
    v = np.asarray(point, float) - np.asarray(seq[0], float)
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def pair(found, truth, radius=TERMINAL_MATCH_PX):
    """Number of `found` points paired one to one with `truth` points within `radius`,
    each found point (in order) taking its nearest free truth."""
    used = [False] * len(truth)
    hits = 0
    for f in found:
        free = [(math.dist(f, t), j) for j, t in enumerate(truth) if not used[j]]
        near = [c for c in free if c[0] <= radius]
        if near:
            used[min(near)[1]] = True
            hits += 1
    return hits


def moved_end(end, cable, shift):
    """The reported `end` moved `shift` pixels along its cable's polyline, inward."""
    line = cable["polyline"]
    index = 0 if math.dist(line[0], end["point"]) <= math.dist(line[-1], end["point"]) else -1
    return list(np.asarray(end["point"]) + shift * inward(line, index))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", default="target/release/ariadne")
    ap.add_argument("--dataset", default=os.environ.get(
        "ARIADNE_DATASET", str(Path(__file__).resolve().parents[2] / "shared/datasets/cables")))
    ap.add_argument("--model", default="out/field-{group}.onnx")
    ap.add_argument("--shifts", default="-6,-3,0,3,6")
    args = ap.parse_args()
    shifts = [float(s) for s in args.shifts.split(",")]
    dev = (Path(args.dataset) / "simple").is_dir() and (Path(args.dataset) / "hard").is_dir()
    rows = {}
    for photo in sorted(Path(args.dataset).glob("*/*.jpg")):
        set_name = photo.parent.name
        group = background_group(set_name, photo.stem) if dev else set_name
        cmd = [args.binary, "segment", str(photo), "--json", "-",
               "--model", args.model.format(group=group)]
        if dev and set_name == "hard":
            cmd += ["--preset", "clutter"]  # as ariadne eval runs the hard set
        out = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
        width, height = Image.open(photo).size
        lines = read_lines(photo.with_suffix(".txt"))
        truth, offsets = [], []
        ends = sorted(out["endpoints"], key=lambda e: -e["confidence"])
        for line in lines:
            for index in (0, -1):
                t = line[index]
                if min(t[0], t[1], width - 1 - t[0], height - 1 - t[1]) < BORDER_TOLERANCE_PX:
                    continue
                truth.append([float(t[0]), float(t[1])])
                near = min(ends, key=lambda e: math.dist(e["point"], t), default=None)
                if near is not None and math.dist(near["point"], t) <= NEAR_PX:
                    offsets.append(float((np.asarray(near["point"]) - t) @ inward(line, index)))
        cables = {c["id"]: c for c in out["cables"]}
        row = rows.setdefault(group, {"terminals": 0, "offsets": [], "hits": [0] * len(shifts)})
        row["terminals"] += len(truth)
        row["offsets"] += offsets
        for k, shift in enumerate(shifts):
            points = [e["point"] if e["cable"] is None else moved_end(e, cables[e["cable"]], shift)
                      for e in ends]
            row["hits"][k] += pair(points, truth)
    print("| group | terminals | ends within 30 px | offset along the cable, median (quartiles), px | "
          + " | ".join(f"recall, moved {s:+g} px" for s in shifts) + " |")
    print("|---" * (4 + len(shifts)) + "|")
    for group, r in rows.items():
        q1, med, q3 = np.percentile(r["offsets"], [25, 50, 75]) if r["offsets"] else (0, 0, 0)
        print(f"| {group} | {r['terminals']} | {len(r['offsets'])} | {med:+.1f} ({q1:+.1f}, {q3:+.1f}) | "
              + " | ".join(f"{h / max(r['terminals'], 1):.3f}" for h in r["hits"]) + " |")


if __name__ == "__main__":
    main()
