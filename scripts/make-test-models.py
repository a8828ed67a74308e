#!/usr/bin/env python3
"""Writes the tiny ONNX models tests/detector.rs loads to check start-up errors: inputs
the service cannot feed. Each is an Identity graph of a few hundred bytes.

    training/.venv/bin/python scripts/make-test-models.py
"""

from pathlib import Path

import onnx
from onnx import TensorProto, helper

OUT = Path(__file__).resolve().parent.parent / "tests" / "models"


def identity(name: str, shape: list) -> None:
    image = helper.make_tensor_value_info("image", TensorProto.FLOAT, shape)
    field = helper.make_tensor_value_info("field", TensorProto.FLOAT, shape)
    graph = helper.make_graph([helper.make_node("Identity", ["image"], ["field"])],
                              name, [image], [field])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.checker.check_model(model)
    onnx.save(model, OUT / f"{name}.onnx")


if __name__ == "__main__":
    OUT.mkdir(parents=True, exist_ok=True)
    identity("one_side_fixed", [1, 3, 240, "width"])
    identity("one_channel", [1, 1, "height", "width"])
