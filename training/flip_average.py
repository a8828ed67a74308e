"""Exports a trained cable-field network with test-time flip averaging built in.

The exported graph runs the network on the photo and on its mirror image, mirrors the
second output back and combines the two: the mirrored x offset becomes 1 - x and
sin 2θ changes sign (a horizontal mirror maps θ to π - θ); cos 2θ and the y offset stay.
`--heat mean` averages every channel; `--heat max` keeps the larger terminal
probability of the two (more peaks) and averages the cable and direction channels,
with the offsets of the unmirrored pass. Same input and output as the network, so the
engine runs it unchanged:

    training/.venv/bin/python training/flip_average.py out/field-hard-fp32.pt --out out/flip-hard.onnx
    python3 scripts/lobo.py --binary target/release/ariadne --models 'out/flip-{group}.onnx'

Measured leave-one-background-out and not adopted (models/README.md, "Flip averaging").
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import torch

from backbone import LiteFieldNet
from train_field import CHANNELS, export_onnx


class FlipAveraged(torch.nn.Module):
    """`net` on the photo and on its mirror image, combined (module docs)."""

    def __init__(self, net: torch.nn.Module, heat: str):
        super().__init__()
        self.net, self.heat = net, heat

    def forward(self, x):
        a = self.net(x)
        b = self.net(torch.flip(x, [3])).flip([3])
        b = torch.cat([b[:, :2], 1 - b[:, 2:3], b[:, 3:5], -b[:, 5:6]], 1)
        if self.heat == "mean":
            return (a + b) / 2
        terminal = torch.maximum(a[:, 1:2], b[:, 1:2])
        return torch.cat([(a[:, :1] + b[:, :1]) / 2, terminal, a[:, 2:4],
                          (a[:, 4:] + b[:, 4:]) / 2], 1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("weights", help="a .pt written by train_field.py (its .train.json beside it)")
    ap.add_argument("--heat", choices=["mean", "max"], default="mean")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    weights = Path(args.weights)
    trained = json.loads(weights.with_suffix(".train.json").read_text())["args"]
    if trained["backbone"] != "lite0":
        raise SystemExit("only the lite0 backbone (the bundled recipe) is supported")
    net = LiteFieldNet(CHANNELS, trained["width"])
    net.load_state_dict(torch.load(weights))
    model = FlipAveraged(net.eval(), args.heat).eval()
    export_onnx(model, Path(args.out))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
