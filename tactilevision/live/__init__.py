"""Live processing: a frame pipeline for a robot's perception loop (``tactilevision live``).

:class:`Pipeline` (or :func:`stream`) takes a camera index, a video file, a frame
folder or any iterable of frames, captures on its own thread under a stated
policy (``'latest'``: drop stale frames when processing is slower than the
camera; ``'every'``: process every frame), and yields one :class:`LiveResult`
per frame: capture time, latency, height map, contact mask, force map and
total force.
"""

from ._pipeline import LiveResult, Pipeline, auto_reference, open_frames, stream

__all__ = ["LiveResult", "Pipeline", "auto_reference", "open_frames", "stream"]
