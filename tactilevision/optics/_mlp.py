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

__all__ = ["MLPGradientModel", "cell_position_inputs", "default_position_cell_px", "mlp_inputs",
           "mlp_layers", "train_mlp"]

N_INPUTS = 8
#: Pixels per optimisation step of :func:`train_mlp` (its default batch).
BATCH_SIZE = 4096


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


def default_position_cell_px(shape: tuple[int, int]) -> int:
    """The position cell of a new network: ``max(H, W) // 16`` px, at least 20.

    Sixteen cells along the frame's long side, so the network's table
    (:func:`~tactilevision.optics._table.tabulate_mlp`) holds at most 16 x 12
    cells of 32^3 colours whatever the resolution (25 MB, 2 to 3 s to tabulate
    on 2 cores): 20 px at 320 x 240, 26 px at 427 x 320, 40 px at 640 x 480;
    smaller frames keep 20 px cells, and fewer of them.

    Parameters
    ----------
    shape : (H, W)

    Returns
    -------
    cell_px : int
    """
    return max(20, max(int(shape[0]), int(shape[1])) // 16)


def cell_position_inputs(ref_colour: np.ndarray, cell_px: int
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The position and reference inputs of a cell-snapped network, per pixel.

    A network calibrated with ``position_cell_px`` sees, at every pixel, the
    centre of its square position cell and the cell's mean reference colour,
    instead of the pixel's own: its output is then constant over a cell for a
    given colour change, so a table over colour cells and these position cells
    (:func:`~tactilevision.optics._table.tabulate_mlp`) reproduces it up to the
    colour quantisation alone. Cell (i, j) covers rows ``[i c, min((i + 1) c,
    H))`` and columns likewise, c = `cell_px`; its centre is the middle of
    those pixel centres.

    Parameters
    ----------
    ref_colour : (H, W, 3) float ndarray
        Smoothed reference colour, 0..255.
    cell_px : int
        Cell size, px (positive).

    Returns
    -------
    ref_cell : (H, W, 3) float32 ndarray
        Each pixel's cell mean of `ref_colour`.
    x_cell, y_cell : (H, W) float32 ndarray
        Each pixel's cell centre, px (column, row).
    """
    h, w = ref_colour.shape[:2]
    c = int(cell_px)
    ny, nx = -(-h // c), -(-w // c)
    rows = np.minimum(np.arange(h) // c, ny - 1)
    cols = np.minimum(np.arange(w) // c, nx - 1)
    starts_y, starts_x = np.arange(ny) * c, np.arange(nx) * c
    centre_y = (starts_y + np.minimum(starts_y + c, h) - 1) / 2.0
    centre_x = (starts_x + np.minimum(starts_x + c, w) - 1) / 2.0
    ref = np.asarray(ref_colour, np.float64)
    # cell sums: np.add.reduceat over the cell starts along rows, then columns
    sums = np.add.reduceat(np.add.reduceat(ref, starts_y, axis=0), starts_x, axis=1)
    counts = np.outer(np.diff(np.append(starts_y, h)), np.diff(np.append(starts_x, w)))
    means = (sums / counts[..., None]).astype(np.float32)
    ref_cell = means[rows[:, None], cols[None, :]]
    x_cell = np.broadcast_to(centre_x[cols][None, :], (h, w)).astype(np.float32)
    y_cell = np.broadcast_to(centre_y[rows][:, None], (h, w)).astype(np.float32)
    return ref_cell, x_cell, y_cell


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


def mlp_layers(onnx_bytes: bytes) -> list[tuple[np.ndarray, np.ndarray]]:
    """The layers of a network written by :func:`train_mlp`.

    Parameters
    ----------
    onnx_bytes : bytes
        ONNX bytes of this library's SiLU network (initialisers ``W0``,
        ``b0``, ``W1``, ...), the input standardisation folded into ``W0``.

    Returns
    -------
    layers : list of (W (out, in), b (out,)) float64 ndarray pairs

    Raises
    ------
    InputError
        If the bytes are not such a network (e.g. gs_sdk's convolutional one).
    """
    import onnx
    from onnx import numpy_helper

    try:
        model = onnx.load_from_string(onnx_bytes)
    except Exception as exc:                    # protobuf's DecodeError and kin
        raise InputError(f"not an ONNX network: {exc}") from None
    if model.graph.name != "tactilevision_normal_mlp":
        raise InputError(f"the network {model.graph.name!r} is not this library's colour-to-"
                         "normal MLP (train_mlp); it cannot be a warm start")
    inits = {t.name: numpy_helper.to_array(t).astype(np.float64)
             for t in model.graph.initializer}
    return [(inits[f"W{k}"], inits[f"b{k}"]) for k in range(len(inits) // 2)]


def _standardised_layers(layers: list[tuple[np.ndarray, np.ndarray]], mean: np.ndarray,
                         std: np.ndarray, hidden: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """`layers` (raw inputs) with the first layer acting on ``(x - mean) / std``:
    ``W x + b = (W std) z + (b + W mean)``."""
    shapes = [(hidden, N_INPUTS), (hidden, hidden), (2, hidden)]
    if [w.shape for w, _ in layers] != shapes:
        raise InputError(f"the warm-start network's layers are "
                         f"{[w.shape for w, _ in layers]}, not {shapes} (hidden={hidden})")
    w0, b0 = layers[0]
    return [(w0 * std[None, :], b0 + w0 @ mean), *layers[1:]]


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
              batch_size: int = BATCH_SIZE, learning_rate: float = 3e-3, seed: int = 0,
              progress: bool = False, max_steps: int | None = None,
              init: bytes | None = None) -> bytes:
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
    init : bytes, optional
        A network of this shape (ONNX bytes from this function, `hidden`
        units) to start from instead of a random initialisation: a warm
        start, e.g. on labels that moved a little. Its weights are carried
        into this data's standardisation exactly (the network's output on
        any input is unchanged before the first step).

    Returns
    -------
    onnx_bytes : bytes
        The trained network, input standardisation folded in.

    Raises
    ------
    ImportError
        If torch or onnx is missing: ``pip install tactilevision[torch]``.
    InputError
        For a ``max_steps`` that is not a positive integer, or an `init`
        that is not a network of this shape.
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
    if init is not None:
        start = _standardised_layers(mlp_layers(init), mean, std, hidden)
        with torch.no_grad():
            for m, (w, b) in zip([m for m in net if isinstance(m, torch.nn.Linear)], start,
                                 strict=True):
                m.weight.copy_(torch.from_numpy(w.astype(np.float32)))
                m.bias.copy_(torch.from_numpy(b.astype(np.float32)))
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
