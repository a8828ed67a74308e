#!/usr/bin/env python3
"""Trains a tiny ultralytics YOLO detector of cable ends and exports it the three ways
users do, into tests/models/ for tests/yolo.rs:

    yolo_fixed.onnx     imgsz 240x320, raw head output [1, 5, N]
    yolo_dynamic.onnx   dynamic=True: free height and width, multiples of 32
    yolo_nms.onnx       nms=True: [1, 300, 6] (x1, y1, x2, y2, score, class)
    yolo_expected.json  ultralytics' own predictions with yolo_fixed.onnx on
                        simple/00000.jpg (box centres, scores): the reference for
                        the service's letterbox and decoding

The network is `training/yolo/tiny-ends.yaml` (a few hundred KB), trained from scratch
for a few minutes on CPU on the development split: one box of 24x24 px around every
centreline end in view. It is a plumbing test, not a good detector. Needs ultralytics in
the training environment (`training/yolo/requirements.txt`):

    training/.venv/bin/pip install -r training/yolo/requirements.txt
    training/.venv/bin/python scripts/make-yolo-test-models.py
    training/.venv/bin/python scripts/make-yolo-test-models.py --expected-only
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "training"))

import scenes  # noqa: E402  (training/scenes.py: the dataset reader)
from PIL import Image  # noqa: E402
from ultralytics import YOLO  # noqa: E402

OUT = ROOT / "tests" / "models"
BOX_PX = 24.0


def write_dataset(root: Path, work: Path) -> Path:
    """The development split in YOLO's layout: images/ and labels/ side by side."""
    (work / "images").mkdir(parents=True)
    (work / "labels").mkdir(parents=True)
    for set_name in ("simple", "hard"):
        for jpg in sorted((root / set_name).glob("*.jpg")):
            w, h = Image.open(jpg).size
            lines = scenes.read_lines(jpg.with_suffix(".txt"))
            ends = scenes.terminals(lines, w, h, scenes.BORDER_TOLERANCE_PX)
            name = f"{set_name}-{jpg.stem}"
            shutil.copy(jpg, work / "images" / f"{name}.jpg")
            rows = [f"0 {x / w:.6f} {y / h:.6f} {BOX_PX / w:.6f} {BOX_PX / h:.6f}"
                    for x, y in ends]
            (work / "labels" / f"{name}.txt").write_text("\n".join(rows) + "\n")
    data = work / "ends.yaml"
    data.write_text(f"path: {work}\ntrain: images\nval: images\nnames:\n  0: end\n")
    return data


def write_expected(root: Path):
    """Ultralytics' predictions (its letterbox, its decoding) on one photo."""
    model = YOLO(str(OUT / "yolo_fixed.onnx"), task="detect")
    photo = root / "simple" / "00000.jpg"
    boxes = model.predict(str(photo), imgsz=(256, 320), conf=0.25, verbose=False)[0].boxes
    ends = sorted(([round(float(x), 2), round(float(y), 2), round(float(c), 4)]
                   for (x, y), c in zip(boxes.xywh[:, :2].tolist(), boxes.conf.tolist())),
                  key=lambda e: -e[2])
    doc = {"photo": "simple/00000.jpg", "imgsz": [256, 320], "conf": 0.25, "ends": ends}
    (OUT / "yolo_expected.json").write_text(json.dumps(doc, indent=1) + "\n")
    print(f"wrote {OUT / 'yolo_expected.json'} ({len(ends)} ends)")


def main():
    root = Path(os.environ.get("ARIADNE_DATASET", ROOT.parent / "shared/datasets/cables"))
    OUT.mkdir(parents=True, exist_ok=True)
    if "--expected-only" in sys.argv:
        write_expected(root)
        return
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        data = write_dataset(root, work / "data")
        model = YOLO(str(ROOT / "training/yolo/tiny-ends.yaml"))
        model.train(data=str(data), epochs=int(os.environ.get("EPOCHS", 150)), imgsz=320,
                    batch=8, workers=0, device="cpu", seed=5, deterministic=True,
                    project=str(work / "runs"), name="tiny", plots=False, val=False,
                    amp=False, verbose=False)
        exports = {
            "yolo_fixed": dict(imgsz=(240, 320)),
            "yolo_dynamic": dict(imgsz=(240, 320), dynamic=True),
            "yolo_nms": dict(imgsz=(240, 320), nms=True),
        }
        for name, args in exports.items():
            path = Path(model.export(format="onnx", simplify=True, opset=17, **args))
            shutil.move(path, OUT / f"{name}.onnx")
            print(f"wrote {OUT / f'{name}.onnx'} ({(OUT / f'{name}.onnx').stat().st_size} bytes)")
    write_expected(root)


if __name__ == "__main__":
    main()
