"""A colour-to-gradient network trained with gs_sdk, run as a tactilevision calibration.

gs_sdk (GelSight and CMU's Robotics and Perception Lab; GPL-3.0, none of its code is
used here) calibrates a sensor with a per-pixel network, ``BGRXYMLPNet``, 5 -> 32 -> 32
-> 32 -> 2 with a ReLU after the first three layers, in one of two forms:

- today's (gs_sdk's ``gs_reconstruct.py`` since 2025): four ``nn.Linear`` layers,
  state dict keys ``fc1.weight``, ``fc1.bias``, ..., ``fc4.bias``, no batch
  normalisation;
- the older one: 1 x 1 convolutions ``conv1`` ... ``conv4`` with batch normalisation
  ``bn1`` ... ``bn3`` after the first three.

Either is recognised from the state dict's keys. The network takes the features
(B, G, R) / 255 and (x / W, y / H) of a frame and is trained to the
gradient *angles* (atan of the surface slope) of ball presses:
``atan2(x - x_c, sqrt(R^2 - d^2))`` along x, the same along y (its
``calibration/prepare_data.py``). At run time it takes the tangent and subtracts the
network's output on the no-contact frame (its ``Reconstructor.load_bg``).

:func:`gs_sdk_layers` folds the batch normalisation (running statistics, eval mode)
into the convolutions; :func:`onnx_from_gs_sdk` writes an ONNX graph with this
project's network signature (input ``x`` (M, 8): colour change, reference colour,
position in [-1, 1]; output ``nxy`` (M, 2): the in-plane normal of the depth surface),
which recovers gs_sdk's features from ours, runs the network on the frame and on the
reference, takes the tangents' difference and turns gs_sdk's surface slope (height
towards the camera) into our depth slope (into the gel) and its normal.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Mapping

import numpy as np

from .._checks import InputError
from ._mlp import serialise_normal_graph

__all__ = ["gs_sdk_layers", "onnx_from_gs_sdk"]


def _array(v) -> np.ndarray:
    if hasattr(v, "detach"):                       # a torch tensor
        v = v.detach().cpu().numpy()
    return np.asarray(v, np.float64)


def gs_sdk_layers(state_dict: Mapping[str, object], *, eps: float = 1e-5
                  ) -> list[tuple[np.ndarray, np.ndarray]]:
    """The layers of a gs_sdk ``BGRXYMLPNet`` state dict, batch normalisation folded in.

    Parameters
    ----------
    state_dict : mapping of str to array_like
        Today's form, ``fc<k>.weight`` (out, in) and ``fc<k>.bias`` for
        k = 1, 2, ... (``nn.Linear``, no batch normalisation); or the older
        form, ``conv<k>.weight`` (out, in, 1, 1) or (out, in) and
        ``conv<k>.bias``, with ``bn<k>.weight``, ``.bias``, ``.running_mean``,
        ``.running_var`` after each convolution but the last (torch tensors or
        numpy arrays). A ``module.`` prefix (``nn.DataParallel``) is allowed.
    eps : float, default 1e-5
        torch's ``BatchNorm2d`` epsilon.

    Returns
    -------
    layers : list of (W (out, in), b (out,)) float64 ndarray
        Affine layers, a ReLU between each two; the first takes 5 inputs, the
        last gives 2.

    Raises
    ------
    InputError
        For a state dict of neither form or of another shape (naming the key
        at fault).
    """
    state = {(k[len("module."):] if k.startswith("module.") else k): v
             for k, v in state_dict.items()}
    forms = {}
    for prefix in ("fc", "conv"):
        forms[prefix] = sorted({int(m[1]) for k in state
                                if (m := re.fullmatch(rf"{prefix}(\d+)\.weight", k))})
    prefix = "fc" if forms["fc"] else "conv"
    index = forms[prefix]
    if not index or index != list(range(1, len(index) + 1)) or (forms["fc"] and forms["conv"]):
        raise InputError("not a gs_sdk BGRXYMLPNet state dict: it needs fc1.weight, "
                         "fc2.weight, ... (today's gs_sdk) or conv1.weight, conv2.weight, ... "
                         f"(older gs_sdk); it has {sorted(state)[:8]}")
    batch_norm = prefix == "conv"
    layers = []
    for i, k in enumerate(index):
        w = _array(state[f"{prefix}{k}.weight"])
        if w.ndim not in (2, 4) or (w.ndim == 4 and w.shape[2:] != (1, 1)):
            raise InputError(f"gs_sdk state dict: {prefix}{k}.weight has shape {w.shape}, "
                             "not (out, in) or (out, in, 1, 1)")
        w = w.reshape(w.shape[0], -1)
        b = _array(state.get(f"{prefix}{k}.bias", np.zeros(w.shape[0])))
        if b.shape != (w.shape[0],):
            raise InputError(f"gs_sdk state dict: {prefix}{k}.bias has shape {b.shape}, "
                             f"its weight {w.shape[0]} outputs")
        if batch_norm and i < len(index) - 1:
            need = [f"bn{k}.{p}" for p in ("weight", "bias", "running_mean", "running_var")]
            missing = [n for n in need if n not in state]
            if missing:
                raise InputError(f"gs_sdk state dict: conv{k} has no {missing[0]}")
            g, beta, mean, var = (_array(state[n]) for n in need)
            scale = g / np.sqrt(var + eps)
            w = w * scale[:, None]
            b = (b - mean) * scale + beta
        layers.append((w, b))
    if layers[0][0].shape[1] != 5 or layers[-1][0].shape[0] != 2:
        raise InputError(f"gs_sdk network: {layers[0][0].shape[1]} inputs and "
                         f"{layers[-1][0].shape[0]} outputs, expected 5 (B, G, R, x, y) and 2")
    for (w0, _), (w1, _) in itertools.pairwise(layers):
        if w1.shape[1] != w0.shape[0]:
            raise InputError(f"gs_sdk network: a layer of {w0.shape[0]} outputs feeds one of "
                             f"{w1.shape[1]} inputs")
    return layers


def onnx_from_gs_sdk(layers: list[tuple[np.ndarray, np.ndarray]], shape: tuple[int, int]
                     ) -> bytes:
    """An ONNX graph with this project's network signature around a gs_sdk network.

    Parameters
    ----------
    layers : list of (W, b)
        From :func:`gs_sdk_layers`.
    shape : (H, W)
        Frame size: gs_sdk's position features are x / W and y / H.

    Returns
    -------
    onnx_bytes : bytes
        Input ``x`` (M, 8) float32 as :func:`mlp_inputs` (colour change c,
        reference colour r / 255, x and y in [-1, 1]); output ``nxy`` (M, 2):
        with gs_sdk's features f = ((1 + c) r, x / W, y / H) and f0 = (r, x / W,
        y / H), its slope G = tan(net(f)) - tan(net(f0)); the depth slope is
        g = -G and the output ``(-g_x, -g_y) / sqrt(1 + |g|^2)``
        (:func:`normals_from_gradients`).

    Raises
    ------
    ImportError
        Without the ``onnx`` package (the torch extra).
    """
    from onnx import helper, numpy_helper

    h, w = shape
    inits = [
        numpy_helper.from_array(np.array([1], np.int64), "ax1"),
        numpy_helper.from_array(np.array([1.0], np.float32), "one"),
        # x in [-1, 1] -> x / W: (x + 1) (W - 1) / (2 W)
        numpy_helper.from_array(np.array([(w - 1) / (2.0 * w), (h - 1) / (2.0 * h)],
                                         np.float32), "pos_scale"),
    ]
    nodes = []
    # split the (M, 8) input into change (M, 3), reference (M, 3), position (M, 2)
    for name, lo, hi in (("chg", 0, 3), ("ref", 3, 6), ("pos", 6, 8)):
        inits += [numpy_helper.from_array(np.array([lo], np.int64), f"{name}_lo"),
                  numpy_helper.from_array(np.array([hi], np.int64), f"{name}_hi")]
        nodes.append(helper.make_node("Slice", ["x", f"{name}_lo", f"{name}_hi", "ax1"],
                                      [name]))
    nodes += [
        helper.make_node("Add", ["chg", "one"], ["chg1"]),
        helper.make_node("Mul", ["chg1", "ref"], ["bgr"]),
        helper.make_node("Add", ["pos", "one"], ["pos1"]),
        helper.make_node("Mul", ["pos1", "pos_scale"], ["xy"]),
        helper.make_node("Concat", ["bgr", "xy"], ["f"], axis=1),
        helper.make_node("Concat", ["ref", "xy"], ["f0"], axis=1),
    ]
    for k, (wk, bk) in enumerate(layers):
        inits += [numpy_helper.from_array(wk.astype(np.float32), f"W{k}"),
                  numpy_helper.from_array(bk.astype(np.float32), f"b{k}")]
    for tag in ("f", "f0"):
        cur = tag
        for k in range(len(layers)):
            out = f"{tag}_l{k}"
            nodes.append(helper.make_node("Gemm", [cur, f"W{k}", f"b{k}"], [out], transB=1))
            if k < len(layers) - 1:
                nodes.append(helper.make_node("Relu", [out], [f"{out}_r"]))
                out = f"{out}_r"
            cur = out
        nodes.append(helper.make_node("Tan", [cur], [f"{tag}_tan"]))
    nodes += [
        # gs_sdk's surface slope G; our depth slope g = -G; normal (-g, 1) / |.| -> G / |.|
        helper.make_node("Sub", ["f_tan", "f0_tan"], ["G"]),
        helper.make_node("Mul", ["G", "G"], ["G2"]),
        helper.make_node("ReduceSum", ["G2", "ax1"], ["G2s"], keepdims=1),
        helper.make_node("Add", ["G2s", "one"], ["G2s1"]),
        helper.make_node("Sqrt", ["G2s1"], ["norm"]),
        helper.make_node("Div", ["G", "norm"], ["nxy"]),
    ]
    return serialise_normal_graph(nodes, inits, "gs_sdk_bgrxy_mlp",
                                  "tactilevision (gs_sdk import)")
