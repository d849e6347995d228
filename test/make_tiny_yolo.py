#!/usr/bin/python3
"""Writes tiny synthetic YOLOv8-style ONNX models for test/test_yolo.cpp.

Run with Debian's interpreter (python3-onnx, python3-numpy):
    /usr/bin/python3 test/make_tiny_yolo.py OUT_DIR [--size S]
writes OUT_DIR/tiny_yolo_S.onnx (head [1, 6, A], the YOLOv8 export layout) and
OUT_DIR/tiny_yolo_S_t.onnx (the same head transposed, [1, A, 6]).

The model (opset 12, only ops Debian's OpenCV 4.6 dnn runs: MaxPool, Conv, Slice, Add of equal
shapes, Sigmoid, Concat, Reshape, Transpose). Input x: [1, 3, S, S], values in [0, 1] (channel 0, 1 =
gray, 2 = depth as 8 bits, / 255). Output: 2 classes, one anchor per 8 × 8 cell (G = S / 8, A = G²,
anchor a = i·G + j for cell row i, column j). With g0, g1, d the maxima of channels 0, 1, 2 over the
cell:
    cx = 8·j + 4,   cy = 8·i + 4          (the cell centre, input px)
    w  = 64·g0,     h  = 32·g1            (input px)
    class 0 score = sigmoid(20·d − 12)    (≥ 0.5 when d ≥ 0.6)
    class 1 score = sigmoid(20·g0 − 18)   (≥ 0.5 when g0 ≥ 0.9)
"""
import argparse
import os

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

CELL = 8  # pooling cell (input px)
NC = 2    # classes


def build(size, transposed):
    g = size // CELL
    anchors = g * g
    f32 = np.float32

    # 1×1 convolution over the pooled channels (g0, g1, d): rows = output channels
    # (cx, cy, w, h, logit0, logit1), columns = input channels.
    weight = np.array([[0, 0, 0],
                       [0, 0, 0],
                       [64, 0, 0],
                       [0, 32, 0],
                       [0, 0, 20],
                       [20, 0, 0]], f32).reshape(4 + NC, 3, 1, 1)
    bias = np.array([0, 0, 0, 0, -12, -18], f32)

    # Cell centres for channels cx, cy (full shape [1, 4, G, G]: OpenCV 4.6 fails on broadcast Add).
    grid = np.zeros((1, 4, g, g), f32)
    grid[0, 0] = (np.arange(g, dtype=f32) * CELL + CELL / 2)[None, :]
    grid[0, 1] = (np.arange(g, dtype=f32) * CELL + CELL / 2)[:, None]

    inits = [
        numpy_helper.from_array(weight, "W"),
        numpy_helper.from_array(bias, "B"),
        numpy_helper.from_array(grid, "grid"),
        numpy_helper.from_array(np.array([0], np.int64), "box_start"),
        numpy_helper.from_array(np.array([4], np.int64), "box_end"),
        numpy_helper.from_array(np.array([4 + NC], np.int64), "cls_end"),
        numpy_helper.from_array(np.array([1], np.int64), "axis1"),
        numpy_helper.from_array(np.array([1, 4 + NC, anchors], np.int64), "head_shape"),
    ]
    nodes = [
        helper.make_node("MaxPool", ["x"], ["pooled"], kernel_shape=[CELL, CELL],
                         strides=[CELL, CELL]),
        helper.make_node("Conv", ["pooled", "W", "B"], ["lin"], kernel_shape=[1, 1]),
        helper.make_node("Slice", ["lin", "box_start", "box_end", "axis1"], ["box_rel"]),
        helper.make_node("Add", ["box_rel", "grid"], ["box"]),
        helper.make_node("Slice", ["lin", "box_end", "cls_end", "axis1"], ["logits"]),
        helper.make_node("Sigmoid", ["logits"], ["cls"]),
        helper.make_node("Concat", ["box", "cls"], ["grid_head"], axis=1),
        helper.make_node("Reshape", ["grid_head", "head_shape"],
                         ["head"] if transposed else ["y"]),
    ]
    out_shape = [1, 4 + NC, anchors]
    if transposed:
        nodes.append(helper.make_node("Transpose", ["head"], ["y"], perm=[0, 2, 1]))
        out_shape = [1, anchors, 4 + NC]

    x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 3, size, size])
    y = helper.make_tensor_value_info("y", TensorProto.FLOAT, out_shape)
    graph = helper.make_graph(nodes, "tiny_yolo", [x], [y], initializer=inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 12)],
                              producer_name="fact make_tiny_yolo.py")
    model.ir_version = 7
    onnx.checker.check_model(model)
    return model


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir")
    parser.add_argument("--size", type=int, default=160, help="input side S (multiple of 8)")
    args = parser.parse_args()
    if args.size <= 0 or args.size % CELL:
        parser.error(f"--size {args.size}: expected a positive multiple of {CELL}")
    os.makedirs(args.out_dir, exist_ok=True)
    for transposed, suffix in ((False, ""), (True, "_t")):
        path = os.path.join(args.out_dir, f"tiny_yolo_{args.size}{suffix}.onnx")
        onnx.save(build(args.size, transposed), path + ".tmp")
        os.replace(path + ".tmp", path)  # atomic: parallel tests may write the same file
        print(path)


if __name__ == "__main__":
    main()
