"""Position-aware colour-to-normal network: trained in torch, run in onnxruntime.

Inputs per pixel: the colour change (3), the reference colour (3) and the
pixel position (x, y), so the network can learn how the shading of a given
normal varies across a pad lit unevenly from its edges. Output: the in-plane
normal components (n_x, n_y). Two hidden layers of SiLU units. The input
standardisation is folded into the first layer, and the network is written
as a plain ONNX graph (Gemm, Sigmoid, Mul), so running it needs only
``onnxruntime``; training needs the ``torch`` extra (torch and onnx).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import onnxruntime as ort
from tqdm.auto import tqdm

from .._checks import InputError, check_array

__all__ = ["MLPGradientModel", "mlp_inputs", "train_mlp"]

N_INPUTS = 8


def mlp_inputs(change: np.ndarray, ref_colour: np.ndarray, x_px: np.ndarray, y_px: np.ndarray,
               shape: tuple[int, int], *, use_position: bool = True) -> np.ndarray:
    """Stack the per-pixel network inputs.

    Parameters
    ----------
    change : (M, 3) float32 ndarray
        Colour change of the pixels.
    ref_colour : (M, 3) float32 ndarray
        Smoothed reference colour at the pixels, 0..255.
    x_px, y_px : (M,) ndarray
        Pixel column and row.
    shape : tuple of int
        (H, W) of the frame, to scale positions to [-1, 1].
    use_position : bool, default True
        When False the position inputs are zero (an ablation: a
        colour-only network).

    Returns
    -------
    inputs : (M, 8) float32 ndarray
    """
    h, w = shape
    out = np.empty((change.shape[0], N_INPUTS), np.float32)
    out[:, 0:3] = change
    out[:, 3:6] = ref_colour * (1.0 / 255.0)
    if use_position:
        out[:, 6] = x_px * (2.0 / (w - 1)) - 1.0
        out[:, 7] = y_px * (2.0 / (h - 1)) - 1.0
    else:
        out[:, 6:8] = 0.0
    return out


@dataclass
class MLPGradientModel:
    """An ONNX colour-to-normal network run through onnxruntime.

    Parameters
    ----------
    onnx_bytes : bytes
        The serialised ONNX model: input ``x`` (M, 8) float32, output
        ``nxy`` (M, 2) float32.
    threads : int, default 1
        onnxruntime intra-op threads (1: one core, as embedded users run it;
        0: all cores).
    """

    onnx_bytes: bytes
    threads: int = 1

    def __post_init__(self) -> None:
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = int(self.threads)
        opts.inter_op_num_threads = 1
        opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        self._session = ort.InferenceSession(self.onnx_bytes, sess_options=opts,
                                             providers=["CPUExecutionProvider"])

    def normals(self, inputs: np.ndarray) -> np.ndarray:
        """Run the network.

        Parameters
        ----------
        inputs : (M, 8) float32 ndarray
            From :func:`mlp_inputs`.

        Returns
        -------
        nxy : (M, 2) float32 ndarray
            In-plane normal components.
        """
        inputs = check_array(inputs, "inputs", [(None, N_INPUTS)], dtype=np.float32)
        if inputs.shape[0] == 0:
            return np.zeros((0, 2), np.float32)
        return self._session.run(None, {"x": np.ascontiguousarray(inputs)})[0]


def _onnx_from_layers(layers: list[tuple[np.ndarray, np.ndarray]]) -> bytes:
    """Serialise a SiLU MLP (list of (W (out, in), b (out,))) as ONNX bytes."""
    from onnx import helper, numpy_helper

    nodes, inits = [], []
    cur = "x"
    for k, (w, b) in enumerate(layers):
        inits += [numpy_helper.from_array(w.astype(np.float32), f"W{k}"),
                  numpy_helper.from_array(b.astype(np.float32), f"b{k}")]
        out = f"h{k}" if k < len(layers) - 1 else "nxy"
        lin = f"lin{k}" if k < len(layers) - 1 else out
        nodes.append(helper.make_node("Gemm", [cur, f"W{k}", f"b{k}"], [lin], transB=1))
        if k < len(layers) - 1:
            nodes.append(helper.make_node("Sigmoid", [lin], [f"sig{k}"]))
            nodes.append(helper.make_node("Mul", [lin, f"sig{k}"], [out]))
        cur = out
    return serialise_normal_graph(nodes, inits, "tactilevision_normal_mlp", "tactilevision")


def serialise_normal_graph(nodes: list, initializers: list, name: str, producer: str) -> bytes:
    """Check and serialise an ONNX graph of this library's network signature: input ``x``
    (M, 8) float32 (:func:`mlp_inputs`), output ``nxy`` (M, 2) float32 (opset 17)."""
    import onnx
    from onnx import TensorProto, helper

    graph = helper.make_graph(
        nodes, name,
        [helper.make_tensor_value_info("x", TensorProto.FLOAT, ["M", N_INPUTS])],
        [helper.make_tensor_value_info("nxy", TensorProto.FLOAT, ["M", 2])],
        initializer=initializers,
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)],
                              producer_name=producer)
    model.ir_version = 8
    onnx.checker.check_model(model)
    return model.SerializeToString()


def train_mlp(inputs: np.ndarray, nxy: np.ndarray, *, hidden: int = 128, epochs: int = 12,
              batch_size: int = 4096, learning_rate: float = 3e-3, seed: int = 0,
              progress: bool = False, max_steps: int | None = None) -> bytes:
    """Train the colour-to-normal network and return it as ONNX bytes.

    Parameters
    ----------
    inputs : (M, 8) float32 ndarray
        From :func:`mlp_inputs`.
    nxy : (M, 2) float32 ndarray
        True in-plane normal components.
    hidden : int, default 128
        Units per hidden layer (two layers).
    epochs : int, default 12
        Passes over the data (Adam, one-cycle learning rate, MSE loss).
    batch_size : int, default 4096
    learning_rate : float, default 3e-3
        Peak learning rate.
    seed : int, default 0
        Seed of the initialisation and the batch order (deterministic on CPU).
    progress : bool, default False
        Show a progress bar over epochs.
    max_steps : int, optional
        The most optimisation steps (batches): with more data than
        ``max_steps / epochs`` batches the training stops there, part-way
        through a pass, the learning-rate cycle fitted to it. None: every
        epoch in full.

    Returns
    -------
    onnx_bytes : bytes
        The trained network, input standardisation folded in.

    Raises
    ------
    ImportError
        If torch or onnx is missing: ``pip install tactilevision[torch]``.
    InputError
        For a ``max_steps`` that is not a positive integer.
    """
    try:
        import torch
    except ImportError as exc:  # pragma: no cover - exercised without the extra
        raise ImportError("training the MLP needs torch: pip install 'tactilevision[torch]'"
                          " (torch==2.13.0 on this machine)") from exc

    inputs = check_array(inputs, "inputs", [("M", N_INPUTS)], dtype=np.floating, finite=True)
    nxy = check_array(nxy, "nxy", [(inputs.shape[0], 2)], dtype=np.floating, finite=True)
    mean = inputs.mean(axis=0)
    std = inputs.std(axis=0)
    std[std < 1e-6] = 1.0
    gen = torch.Generator().manual_seed(seed)
    torch.manual_seed(seed)
    x = torch.from_numpy(((inputs - mean) / std).astype(np.float32))
    y = torch.from_numpy(nxy.astype(np.float32))
    net = torch.nn.Sequential(
        torch.nn.Linear(N_INPUTS, hidden), torch.nn.SiLU(),
        torch.nn.Linear(hidden, hidden), torch.nn.SiLU(),
        torch.nn.Linear(hidden, 2),
    )
    if max_steps is not None and (isinstance(max_steps, bool) or int(max_steps) != max_steps
                                  or max_steps < 1):
        raise InputError(f"max_steps must be a positive integer or None, got {max_steps!r}")
    per_epoch = (len(x) + batch_size - 1) // batch_size
    steps = epochs * per_epoch
    if max_steps is not None:
        steps = min(steps, int(max_steps))
    opt = torch.optim.Adam(net.parameters(), lr=learning_rate)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=learning_rate, total_steps=steps)
    done = 0
    for _ in tqdm(range(-(-steps // per_epoch)), desc="training MLP", unit="epoch",
                  disable=not progress):
        perm = torch.randperm(len(x), generator=gen)
        for k in range(0, len(x), batch_size):
            if done == steps:
                break
            done += 1
            b = perm[k:k + batch_size]
            loss = torch.mean((net(x[b]) - y[b]) ** 2)
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
    lin = [m for m in net if isinstance(m, torch.nn.Linear)]
    layers = [(m.weight.detach().numpy().astype(np.float64),
               m.bias.detach().numpy().astype(np.float64)) for m in lin]
    w0, b0 = layers[0]
    layers[0] = (w0 / std[None, :], b0 - (w0 / std[None, :]) @ mean)
    return _onnx_from_layers(layers)
