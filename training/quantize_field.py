"""Quantizes a trained cable field network to 8-bit integers for the service.

The service runs the network on one core for every photo (about 6 ms of ONNX Runtime in
float at 320x240 on the development machine). Static quantization (ONNX QDQ: int8
weights per output channel, uint8 activations whose ranges are read on calibration
scenes, each cut at the 99.999th percentile of its histogram) runs the middle of the
network with integer kernels: the whole network about 40 % faster (models/README.md,
"8-bit weights and activations"). Two parts stay in float, each for a measured
reason:

- the input normalisation, the stem and the first inverted-residual block: at full and
  half resolution on three to 32 channels, where integer kernels gained no time and the
  8-bit rounding of the first activations cost the most precision;
- the decoder's fuse and head, whose outputs the engine thresholds and samples (cable
  probability, the terminal heatmap and its offsets, the direction).

Calibration reads the scenes in a folder (every `*.jpg` under it), brought to the
network's input size as the service brings a 640x480 photo (half of it). The bundled
recipe (`make quantize-field`) calibrates on drawn scenes of `scripts/stress.py` with a
seed no evaluation uses, so no photo that a figure is measured on, development or
stress, sets a range:

    training/.venv/bin/python scripts/stress.py out/calibration --seed 40 --per-kind 4
    training/.venv/bin/python training/quantize_field.py models/cable_field_fp32.onnx \\
        models/cable_field.onnx --calibration out/calibration

It prints how far the quantized field lies from the float one on the calibration
scenes, per channel (mean absolute difference).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import onnx
import onnxruntime as ort
from onnxruntime.quantization import (CalibrationDataReader, CalibrationMethod, QuantFormat,
                                      QuantType, quant_pre_process, quantize_static)
from PIL import Image

import scenes
from train_field import to_tensor

# Node-name prefixes (as `torch.onnx.export` names LiteFieldNet's layers) kept in float.
FLOAT_NODES = ("/Sub", "/Div", "/_conv_stem/", "/_blocks.0/", "/fuse/", "/head/",
               "/Slice", "/Sigmoid", "/Tanh", "/Concat")


def network_input(path: Path) -> np.ndarray:
    """A scene as the network's input: [1, 3, H, W] float RGB in [0, 1]."""
    image = Image.open(path).convert("RGB").resize((scenes.IN_W, scenes.IN_H), Image.BILINEAR)
    return to_tensor(np.asarray(image))[None]


class Scenes(CalibrationDataReader):
    """Feeds the calibration scenes to ONNX Runtime's range reading, one at a time."""

    def __init__(self, paths: list[Path]):
        self.paths = iter(paths)

    def get_next(self):
        path = next(self.paths, None)
        return None if path is None else {"image": network_input(path)}


def float_nodes(model: onnx.ModelProto) -> list[str]:
    """The nodes to keep in float; fails if a prefix names none (the graph changed)."""
    names = [node.name for node in model.graph.node]
    kept = [name for name in names if name.startswith(FLOAT_NODES)]
    missing = [p for p in FLOAT_NODES if not any(n.startswith(p) for n in names)]
    if missing:
        raise SystemExit(f"no node starts with {missing}: is this a LiteFieldNet export?")
    return kept


def only_standard_opsets(path: Path):
    """Drops the opset imports of ONNX Runtime's own domains, which no node uses."""
    model = onnx.load(str(path))
    used = {node.domain for node in model.graph.node}
    keep = [o for o in model.opset_import if o.domain in used or o.domain in ("", "ai.onnx")]
    del model.opset_import[:]
    model.opset_import.extend(keep)
    onnx.checker.check_model(model)
    onnx.save(model, str(path))


def field_difference(float_model: Path, int_model: Path, paths: list[Path]) -> np.ndarray:
    """Mean absolute difference of the two fields per channel over `paths`."""
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    a = ort.InferenceSession(str(float_model), options, providers=["CPUExecutionProvider"])
    b = ort.InferenceSession(str(int_model), options, providers=["CPUExecutionProvider"])
    diffs = []
    for path in paths:
        x = {"image": network_input(path)}
        fa, fb = a.run(None, x)[0][0], b.run(None, x)[0][0]
        diffs.append(np.abs(fa - fb).reshape(fa.shape[0], -1).mean(axis=1))
    return np.mean(diffs, axis=0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model", type=Path, help="the float network (train_field.py's export)")
    ap.add_argument("out", type=Path, help="where to write the quantized network")
    ap.add_argument("--calibration", type=Path, required=True,
                    help="folder of calibration scenes (every *.jpg under it)")
    args = ap.parse_args()

    scenes = sorted(args.calibration.rglob("*.jpg"))
    if not scenes:
        raise SystemExit(f"no *.jpg under {args.calibration}")
    with tempfile.TemporaryDirectory() as tmp:
        prepared = Path(tmp) / "prepared.onnx"
        # Folds batch norms into the convolutions; the graph's shapes stay symbolic.
        quant_pre_process(str(args.model), str(prepared), skip_symbolic_shape=True)
        kept = float_nodes(onnx.load(str(prepared)))
        quantize_static(str(prepared), str(args.out), Scenes(scenes),
                        quant_format=QuantFormat.QDQ, per_channel=True,
                        activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8,
                        nodes_to_exclude=kept, calibrate_method=CalibrationMethod.Percentile)
    only_standard_opsets(args.out)
    diff = field_difference(args.model, args.out, scenes)
    print(f"{args.out}: {len(scenes)} calibration scenes, {len(kept)} nodes kept in float")
    print("mean |int8 - float| per channel (cable, terminal, dx, dy, cos2θ, sin2θ): "
          + " ".join(f"{d:.4f}" for d in diff))


if __name__ == "__main__":
    main()
