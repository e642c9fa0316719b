"""Photometric calibration from ball presses: colour -> surface normal.

Pressing a ball of known radius R into the gel gives, inside each contact
circle, pixels whose surface normal is known exactly (:mod:`._ball`). Those
pixels, plus flat background pixels far from the contact, train a model from
colour change (and, for the MLP, reference colour and pixel position) to the
in-plane normal (n_x, n_y). This module holds the calibration's constructors and
its file format, on top of its fields (:class:`._calibration_data.CalibrationData`,
which the reconstructor reads) and of the training
(:func:`tactilevision.optics._training.fit_from_ball_presses`).
"""

from __future__ import annotations

import datetime as _dt
import io
import json
import os
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

import numpy as np

from .._assets import KNOWN_SENSORS, default_calibration_path
from .._checks import InputError, check_array
from .._version import __version__
from ._calibration_data import CalibrationData, ModelKind
from ._engine_choice import calibrate_choosing_engine
from ._gs_sdk_net import gs_sdk_layers, onnx_from_gs_sdk
from ._lut import ColourLUT
from ._training import fit_from_ball_presses

__all__ = ["PhotometricCalibration"]

FORMAT_VERSION = 1


class PhotometricCalibration(CalibrationData):
    """A sensor's colour-to-normal model, with its reference frame and scale.

    Build one with :meth:`from_ball_presses` or :meth:`load`; hand it to
    :class:`DepthReconstructor`.

    Attributes
    ----------
    model : {'lut', 'mlp'}
        The colour-to-normal model kind.
    reference : (H, W, 3) uint8 ndarray
        No-contact reference frame (BGR) the model was calibrated against.
    mm_per_px : float
        Image scale on the gel surface, mm per pixel.
    lut : ColourLUT or None
        The binned table (``model == 'lut'``).
    cell_luts : (ny, nx, B, B, B, 2) float32 ndarray or None
        One binned table per position cell (``model == 'lut'`` calibrated
        with ``lut_cells`` other than (1, 1)); the reconstructor then looks
        every pixel up in its cell's table (:func:`fit_cell_luts`).
    onnx_bytes : bytes or None
        The network (``model == 'mlp'``).
    use_position : bool
        Whether the network sees the pixel position.
    markers : bool
        Whether the gel carries marker dots (masked and filled in).
    blur_sigma : float
        Gaussian blur (px) of frames before the colour change.
    reference_blur : float
        Gaussian blur (px) of the reference against its camera noise, default
        2.0; 0 for a network trained on the raw reference (gs_sdk's).
    normalise_gain : bool
        Whether each frame's colour change is divided by its per-channel
        median ratio to the reference (a global exposure change), default
        True; False for gs_sdk's networks, which do not.
    contact_threshold : float
        Colour change (max over channels) above which a pixel is in contact;
        the 99.9th percentile of the calibration frames' background.
    colour_lo, colour_hi : (3,) float32 ndarray
        Colour-change range of the calibration pixels (0.1 and 99.9
        percentiles), the domain of the LUT and of :meth:`out_of_range`.
    position_cell_px : int
        MLP only: 0 for a network that sees every pixel's own position and
        reference colour; else the size of the square position cells whose
        centre and mean reference colour it sees instead
        (:func:`~tactilevision.optics._mlp.cell_position_inputs`), so that its
        table over these cells reproduces it up to the colour quantisation.
    table_lo, table_hi : (3,) float32 ndarray or None
        MLP only: the colour-change range of the network's table (the 1st and
        99th percentiles of the labelled contact pixels, widened to the flat
        gel's 0.1 and 99.9, within ``colour_lo, colour_hi``); None: the
        colour range. Colours beyond it are read at its edge.
    table_order : {0, 1}
        MLP only: the order of the network's table in the default engine
        (:func:`~tactilevision.optics._table.tabulate_mlp`): 0, a value per
        colour cell (32 cells a channel); 1, a value and its slopes along
        the colour axes (16 cells a channel), for a network that was not
        trained on the table's cells. Default 0; 1 for gs_sdk's networks
        (:meth:`from_gs_sdk`).
    provenance : dict
        Source, date, press count, ball radius, version: how it was made.
    shape : (int, int)
        (H, W) of the frames this calibration applies to (a property).
    """

    # ------------------------------------------------------------------ build
    @classmethod
    def from_ball_presses(
        cls,
        reference: np.ndarray,
        frames: np.ndarray,
        centers_px: np.ndarray | None = None,
        radii_px: np.ndarray | None = None,
        *,
        ball_radius_mm: float | np.ndarray,
        mm_per_px: float,
        model: ModelKind | Literal["auto"] = "auto",
        use_position: bool = True,
        markers: bool | None = None,
        label_fraction: float | None = None,
        refine_centers: bool | None = None,
        bins: int = 32,
        lut_cells: tuple[int, int] = (1, 1),
        epochs: int = 30,
        hidden: int = 128,
        blur_sigma: float = 0.0,
        seed: int = 0,
        source: str = "",
        progress: bool = False,
        detect_edge: Literal["contact", "colour"] = "contact",
        flat_fraction: float = 0.03,
        max_steps: int | None = 2400,
        position_cell_px: int | None = None,
        warm_start: PhotometricCalibration | None = None,
        detected: bool | None = None,
    ) -> PhotometricCalibration:
        """Calibrate from frames of a ball pressed into the gel.

        Parameters
        ----------
        reference : (H, W, 3) uint8 ndarray
            No-contact frame, BGR.
        frames : (N, H, W, 3) uint8 ndarray
            Ball presses, BGR, one contact each.
        centers_px : (N, 2) float ndarray, optional
            Contact-circle centres (x = column, y = row), px. None: detected
            (:func:`detect_contact_circles` with ``edge=detect_edge``).
        radii_px : (N,) float ndarray, optional
            Contact-circle radii, px; given together with ``centers_px``. The
            contact circle: where the gel leaves the ball, not the visible
            colour edge a few pixels outside it.
        ball_radius_mm : float or (N,) array_like
            Ball radius R, mm: one for all presses, or one per press (several
            ball sizes in one calibration, as gs_sdk's ``catalog.csv`` lists
            them: :attr:`tactilevision.io.BallPressSet.ball_radius_mm`).
        mm_per_px : float
            Image scale on the gel, mm per px.
        model : {'auto', 'lut', 'mlp'}, default 'auto'
            The engine: ``'lut'`` a binned colour table, ``'mlp'`` the
            position-aware network (needs torch), ``'auto'`` the one of the
            colour table, the table per position cell and (with 8 presses or
            more and torch installed) the network that reads best on presses
            it was not trained on (:func:`~tactilevision.optics.choose_engine`,
            the procedure of ``optics calibrate``'s default ``--model auto``),
            trained on every press; the choice is in
            ``provenance['engine']``. It costs the candidates' trainings
            (ten colour-table folds each, one network) beside one.
        use_position : bool, default True
            MLP only: feed the pixel position (False: colour-only ablation).
        markers : bool, optional
            Whether the gel has marker dots; None detects them (more than 2%
            of the reference's pixels are dark dots).
        label_fraction : float, optional
            Pixels within ``label_fraction * radius`` of the centre are
            labelled. Default 1.0, but 0.85 for circles detected at the colour
            edge (``detect_edge='colour'``), which lies outside the contact.
        refine_centers : bool, optional
            Refit every centre to the first model's gradients and calibrate
            again (:func:`fit_ball_centre`). Default: True for detected
            circles, False for given ones.
        bins : int, default 32
            LUT cells per colour channel.
        lut_cells : (nx, ny), default (1, 1)
            LUT only: position cells, one colour table each, fitted on the
            labelled pixels of the cell grown by half a cell per side
            (:func:`~tactilevision.optics.fit_cell_luts`); cells with under
            2000 such pixels take the colour-only table. (1, 1): the classic
            colour-only LUT. For a pad lit unevenly (Taxim's GelSight shading
            has position terms) (8, 6) with presses that reach the image's
            edges took the sample session's forces at presses >= 0.3 mm from
            0.89-1.04 of the F/T log (60-78 % within 5 %) to 0.96-1.05 (all
            within 5 %) (``benchmarks/bench_forces_session.py``).
        epochs : int, default 30
            MLP training epochs.
        max_steps : int or None, default 2400
            MLP only: the most optimisation steps (batches of 4096 pixels) of
            a round (two with ``refine_centers``); with more labelled pixels
            the training stops part-way through its epochs, so the time no
            longer grows with the folder (on the taxim GelSight presses,
            36 of 640 x 480, 3600 steps otherwise). None: every epoch in full.
        hidden : int, default 128
            MLP units per hidden layer (two layers). On the taxim GelSight
            presses 128 units gave 4.7 degrees and 56 um against 4.9 to 5.0
            degrees and 63 to 66 um with 64 (two seeds each, table engine).
        blur_sigma : float, default 0.0
            Frame blur (px) before the colour change. Off by default: on the
            taxim GelSight and the GelSlim 3.0 frames a blur of 1 to 2 px
            changed the mean normal error by under 0.1 degree.
        seed : int, default 0
            Seed of the background sampling and of the network.
        source : str, optional
            Where the frames came from, stored in ``provenance``.
        progress : bool, default False
            Progress bars.
        detect_edge : {'contact', 'colour'}, default 'contact'
            Detected circles only: the contact edge
            (:func:`locate_contact_edge`: the shoulder where the colour change
            stops growing, so labels reach the rim's steepest slopes) or the
            colour edge (its steepest fall, outside the contact; labelled to
            0.85 of it, the behaviour before the contact edge). On the real
            GelSight presses of ``taxim`` (trained on the even ones, scored on
            the odd against the annotated circles) the contact edge took the
            deepest point from -6.1 % to -0.2 % (LUT) and from -5.1 % to -0.2 %
            (network) of the ball's cap, and the mean normal angle from 5.98 to
            6.33 and from 3.49 to 4.08 degrees (docs/guide/optics.md, "The
            contact edge").
        flat_fraction : float, default 0.03
            Fraction of each press's pixels beyond twice its contact radius
            (markers excluded) trained on as flat gel, 0 < f <= 1. Colour
            changes within the camera's noise may be flat gel or a gentle
            slope; many flat samples teach the model to read them as flat,
            so the gentle slopes (the middle of a contact, the skirt around
            it) read shallow, and few pass the flat gel's noise into the
            gradients, tilting the background. 0.03 favours a quiet
            background; lower it for depth (docs/guide/optics.md, "Flat
            samples", gives the measured trade).
        position_cell_px : int, optional
            MLP with ``use_position`` only: the network sees each pixel's
            position cell (its centre and mean reference colour) instead of the
            pixel, cells of this size (px), so the default ``'table'`` engine
            reproduces it up to the colour quantisation. None:
            ``max(H, W) // 16``, at least 20 (:func:`default_position_cell_px`); 0: every
            pixel's own position and reference (the form before 2026-11-25,
            whose table read 1.2 to 2.1 degrees median and 3.9 to 6.2 at the
            95th percentile from it inside held-out real contacts). With the
            cells the default engine read 0.03 to 0.37 degrees median and 0.05
            to 1.2 at the 95th percentile better than before on those presses
            (``benchmarks/bench_table_engine.py``; docs/validation/optics.md, "The
            table engine against the exact network").
        warm_start : PhotometricCalibration, optional
            A network calibration of the same sensor (frame size, position
            inputs and cells, `hidden`) whose network the training starts
            from, e.g. one trained on most of these presses: every round then
            takes a quarter of a cold round's steps
            (``MLP_WARM_FRACTION``). The second round (detected circles)
            always starts from the first's network. None: a cold start.
        detected : bool, optional
            Whether the circles are detected ones, treated as such (centres
            refitted, radii rescaled to the slope's peak, the colour edge's
            label fraction). None: detected exactly when none are given. True
            with circles given: they are :func:`detect_contact_circles`'s own
            (``edge=detect_edge``), detected once for several calibrations of
            these presses.

        Returns
        -------
        calibration : PhotometricCalibration

        Raises
        ------
        ShapeError
            If frames and reference differ in size or are not uint8 BGR.
        InputError
            If only one of centres and radii is given, a circle is larger
            than the ball, fewer than two presses are given, ``detect_edge``
            is not a known edge, ``flat_fraction`` is outside (0, 1] or
            leaves no flat pixel, a detected press has no contact, or
            `warm_start` is not a network taking the same inputs, or
            ``detected=False`` without circles.
            With ``model='auto'``: ``lut_cells`` other than (1, 1) or a
            ``warm_start`` (each names an engine).
        ImportError
            For ``model='mlp'`` without torch.
        """
        if model == "auto":
            return calibrate_choosing_engine(
                cls, reference, frames, centers_px, radii_px, ball_radius_mm=ball_radius_mm,
                mm_per_px=mm_per_px, detect_edge=detect_edge, flat_fraction=flat_fraction,
                detected=detected, lut_cells=lut_cells, warm_start=warm_start,
                progress=progress, use_position=use_position, markers=markers,
                label_fraction=label_fraction, refine_centers=refine_centers, bins=bins,
                epochs=epochs, hidden=hidden, blur_sigma=blur_sigma, seed=seed, source=source,
                max_steps=max_steps, position_cell_px=position_cell_px)
        return fit_from_ball_presses(
            cls, reference, frames, centers_px, radii_px, ball_radius_mm=ball_radius_mm,
            mm_per_px=mm_per_px, model=model, use_position=use_position, markers=markers,
            label_fraction=label_fraction, refine_centers=refine_centers, bins=bins,
            lut_cells=lut_cells, epochs=epochs, hidden=hidden, blur_sigma=blur_sigma, seed=seed,
            source=source, progress=progress, detect_edge=detect_edge,
            flat_fraction=flat_fraction, max_steps=max_steps,
            position_cell_px=position_cell_px, warm_start=warm_start, detected=detected)

    @classmethod
    def from_gs_sdk(cls, model: str | Path | Mapping[str, Any], reference: np.ndarray, *,
                    mm_per_px: float, source: str = "") -> PhotometricCalibration:
        """A calibration made with gs_sdk, run by this library (no recalibration).

        gs_sdk's per-pixel network (``BGRXYMLPNet``: 1 x 1 convolutions 5 -> 32
        -> 32 -> 32 -> 2 with batch normalisation, on (B, G, R) / 255 and
        (x / W, y / H), giving gradient angles) is folded into this library's
        network form (:func:`~tactilevision.optics._gs_sdk_net.onnx_from_gs_sdk`):
        a ``model='mlp'`` calibration that :class:`DepthReconstructor` runs with
        either engine (``'table'``, tabulated once, or ``'onnx'``, exact), its
        slopes referred to the network's output on `reference` as gs_sdk does.

        Parameters
        ----------
        model : str, Path or mapping
            gs_sdk's saved model (``torch.save(net.state_dict(), path)``, read
            with ``torch.load(weights_only=True)``), or its state dict.
        reference : (H, W, 3) uint8 ndarray
            The no-contact frame (gs_sdk's ``background.png``), BGR.
        mm_per_px : float
            Image scale (gs_sdk's ``1 / ppmm``), mm per px.
        source : str, optional
            Where the model came from, for the provenance.

        Returns
        -------
        PhotometricCalibration

        Raises
        ------
        InputError
            For a missing file, a file that is not a state dict, a state dict
            of another shape, a bad reference or a non-positive scale.
        ImportError
            Without the torch extra (torch to read the file, onnx to write the
            graph): ``pip install 'tactilevision[torch]'``.
        """
        reference = check_array(reference, "reference", [("H", "W", 3)], dtype=np.uint8)
        if not mm_per_px > 0:
            raise InputError(f"mm_per_px must be positive, got {mm_per_px!r}")
        if not isinstance(model, Mapping):
            path = Path(model)
            if not path.is_file():
                raise InputError(f"gs_sdk model {path} does not exist")
            try:
                import torch
            except ImportError as exc:  # pragma: no cover - exercised without the extra
                raise ImportError("reading a gs_sdk model needs torch: pip install "
                                  "'tactilevision[torch]' (torch==2.13.0 on this machine)"
                                  ) from exc
            try:
                state = torch.load(path, map_location="cpu", weights_only=True)
            except Exception as exc:  # torch raises many kinds for a bad file
                raise InputError(f"gs_sdk model {path} is not a torch state dict: "
                                 f"{exc}") from None
            if not isinstance(state, Mapping):
                raise InputError(f"gs_sdk model {path} holds a {type(state).__name__}, not a "
                                 "state dict")
            source = source or str(path)
        else:
            state = model
        layers = gs_sdk_layers(state)
        # gs_sdk feeds its network the raw frame and the raw background, no exposure gain
        cal = cls(model="mlp", reference=reference.copy(), mm_per_px=float(mm_per_px),
                  use_position=True, markers=False, reference_blur=0.0, normalise_gain=False,
                  table_order=1)
        cal.onnx_bytes = onnx_from_gs_sdk(layers, cal.shape)
        cal.provenance = {
            "source": source, "imported_from": "gs_sdk BGRXYMLPNet",
            "layers": [int(layers[0][0].shape[1])] + [int(w.shape[0]) for w, _ in layers],
            "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            "tactilevision": __version__,
        }
        return cal

    # ------------------------------------------------------------------- I/O
    def save(self, path: str | Path) -> Path:
        """Write the calibration to an ``.npz`` file (no pickle).

        Parameters
        ----------
        path : str or Path
            Destination; ``.npz`` is appended when missing.

        Returns
        -------
        path : Path
            The file written (whole: through a temporary file and an atomic
            rename, so an existing file is replaced only by a complete one).
        """
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(path.suffix + ".npz")
        meta = {
            "format_version": FORMAT_VERSION, "model": self.model, "mm_per_px": self.mm_per_px,
            "use_position": self.use_position, "markers": self.markers,
            "blur_sigma": self.blur_sigma, "contact_threshold": self.contact_threshold,
            "reference_blur": self.reference_blur, "normalise_gain": self.normalise_gain,
            "colour_lo": [float(v) for v in self.colour_lo],
            "colour_hi": [float(v) for v in self.colour_hi],
            "position_cell_px": int(self.position_cell_px),
            "table_order": int(self.table_order),
            "provenance": self.provenance,
        }
        if self.table_lo is not None and self.table_hi is not None:
            meta["table_lo"] = [float(v) for v in self.table_lo]
            meta["table_hi"] = [float(v) for v in self.table_hi]
        arrays: dict[str, np.ndarray] = {
            "meta": np.frombuffer(json.dumps(meta).encode(), np.uint8),
            "reference": self.reference,
        }
        if self.lut is not None:
            arrays.update(lut_table=self.lut.table, lut_lo=self.lut.lo, lut_hi=self.lut.hi,
                          lut_counts=self.lut.counts.astype(np.int32))
        if self.cell_luts is not None:
            # normals in [-1, 1]: float16 keeps them to 5e-4 and halves the file (an 8 x 6
            # grid of 32^3 tables: 4.9 MB compressed instead of 11.0 MB)
            arrays["lut_cells"] = np.asarray(self.cell_luts, np.float16)
        if self.onnx_bytes is not None:
            arrays["onnx"] = np.frombuffer(self.onnx_bytes, np.uint8)
        buf = io.BytesIO()
        np.savez_compressed(buf, **arrays)
        path.parent.mkdir(parents=True, exist_ok=True)
        # through a temporary file and an atomic rename: an older file stays whole until
        # the new one is complete
        tmp = path.with_name(f".{path.name}.tmp")
        try:
            tmp.write_bytes(buf.getvalue())
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
        return path

    @classmethod
    def load(cls, path: str | Path) -> PhotometricCalibration:
        """Read a calibration written by :meth:`save`; needs no torch.

        Parameters
        ----------
        path : str or Path
            The ``.npz`` file, or the name of a calibration shipped with the
            package (``'gelsight'``: :data:`tactilevision.KNOWN_SENSORS`),
            which works from any folder after ``pip install``.

        Returns
        -------
        calibration : PhotometricCalibration

        Raises
        ------
        InputError
            If the file is missing, unreadable or not a calibration (names
            the file and the missing key), or the name is not a shipped
            calibration. Optional metadata missing from an older file takes
            the defaults of this class.

        Examples
        --------
        >>> cal = PhotometricCalibration.load("gelsight")   # the shipped GelSight model
        >>> cal.shape
        (480, 640)
        """
        name = str(path)
        path = Path(path)
        if not path.is_file() and name in KNOWN_SENSORS:
            path = default_calibration_path(name)
        if not path.is_file():
            shipped = ", ".join(repr(s) for s in KNOWN_SENSORS)
            raise InputError(f"calibration file {path} does not exist (calibrations shipped "
                             f"with tactilevision, loadable by name: {shipped})")
        try:
            with np.load(path, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
            # a corrupt or cut-off zip raises any of these, some only when an array is read
            raise InputError(f"calibration file {path} is not a readable .npz "
                             f"({type(exc).__name__}: {exc})") from None
        for key in ("meta", "reference"):
            if key not in data:
                raise InputError(f"calibration file {path} lacks the key '{key}'")
        try:
            meta = json.loads(data["meta"].tobytes().decode())
        except (UnicodeDecodeError, json.JSONDecodeError):
            raise InputError(f"calibration file {path} has an unreadable 'meta' record") from None
        if meta.get("format_version", 0) > FORMAT_VERSION:
            raise InputError(f"calibration file {path} has format version "
                             f"{meta['format_version']}; this tactilevision reads up to "
                             f"{FORMAT_VERSION}")
        for key in ("model", "mm_per_px"):
            if key not in meta:
                raise InputError(f"calibration file {path} lacks the metadata key '{key}'")
        model = meta["model"]
        if model not in ("lut", "mlp"):
            raise InputError(f"calibration file {path} names an unknown model {model!r}")
        needed = {"lut": ("lut_table", "lut_lo", "lut_hi", "lut_counts"), "mlp": ("onnx",)}
        for key in needed[model]:
            if key not in data:
                raise InputError(f"calibration file {path} lacks the key '{key}'")
        lut = onnx_bytes = None
        if model == "lut":
            lut = ColourLUT(data["lut_table"], data["lut_lo"], data["lut_hi"],
                            data["lut_counts"].astype(np.int64))
        else:
            onnx_bytes = data["onnx"].tobytes()
        defaults = cls(model=model, reference=data["reference"], mm_per_px=1.0)
        lo = meta.get("colour_lo", lut.lo if lut is not None else defaults.colour_lo)
        hi = meta.get("colour_hi", lut.hi if lut is not None else defaults.colour_hi)
        cell_px, table_order, table_range = _table_meta(meta, path)
        cell_luts = data.get("lut_cells") if model == "lut" else None
        if cell_luts is not None:
            cell_luts = cell_luts.astype(np.float32)
        if cell_luts is not None and (cell_luts.ndim != 6 or lut is None
                                      or cell_luts.shape[2:] != lut.table.shape):
            raise InputError(f"calibration file {path}: 'lut_cells' has shape "
                             f"{cell_luts.shape}, not (ny, nx) + the LUT's "
                             f"{None if lut is None else lut.table.shape}")
        return cls(model=model, reference=data["reference"],
                   mm_per_px=float(meta["mm_per_px"]), lut=lut, cell_luts=cell_luts,
                   onnx_bytes=onnx_bytes,
                   use_position=bool(meta.get("use_position", defaults.use_position)),
                   markers=bool(meta.get("markers", defaults.markers)),
                   blur_sigma=float(meta.get("blur_sigma", defaults.blur_sigma)),
                   contact_threshold=float(meta.get("contact_threshold",
                                                    defaults.contact_threshold)),
                   reference_blur=float(meta.get("reference_blur", defaults.reference_blur)),
                   normalise_gain=bool(meta.get("normalise_gain", defaults.normalise_gain)),
                   colour_lo=np.asarray(lo, np.float32), colour_hi=np.asarray(hi, np.float32),
                   position_cell_px=cell_px, table_lo=table_range[0], table_hi=table_range[1],
                   table_order=int(table_order), provenance=dict(meta.get("provenance", {})))


def _table_meta(meta: dict, path) -> tuple[int, int, tuple]:
    """A calibration file's network-table keys, checked: ``position_cell_px``,
    ``table_order`` and ``(table_lo, table_hi)`` (None, None when absent).

    Raises
    ------
    InputError
        Naming the file and the key at fault.
    """
    cell_px = meta.get("position_cell_px", 0)
    if isinstance(cell_px, bool) or not isinstance(cell_px, int) or cell_px < 0:
        raise InputError(f"calibration file {path}: 'position_cell_px' must be a "
                         f"non-negative integer, got {cell_px!r}")
    table_order = meta.get("table_order", 0)
    if isinstance(table_order, bool) or table_order not in (0, 1):
        raise InputError(f"calibration file {path}: 'table_order' must be 0 or 1, got "
                         f"{table_order!r}")
    table_range: tuple = (None, None)
    if "table_lo" in meta or "table_hi" in meta:
        try:
            table_range = tuple(np.asarray(meta[k], np.float32).reshape(3)
                                for k in ("table_lo", "table_hi"))
        except (KeyError, TypeError, ValueError):
            raise InputError(f"calibration file {path}: 'table_lo' and 'table_hi' must "
                             "both be three numbers") from None
        if not (np.all(np.isfinite(table_range)) and np.all(table_range[0] < table_range[1])):
            raise InputError(f"calibration file {path}: 'table_lo' must lie below "
                             "'table_hi', both finite")
    return cell_px, table_order, table_range
