"""Cost of the contact mask a frame (``tactilevision.contact.contact_mask``), the step that
certification runs on every frame of a session, beside decoding the frame in the same run.

Run: ``python benchmarks/bench_contact_mask.py`` (a few seconds).
"""

from __future__ import annotations

import time
from pathlib import Path

from tactilevision.contact import contact_mask, noise_level
from tactilevision.io import read_session

SESSION = Path(__file__).resolve().parents[1] / "sample_frames" / "gelsight_session"


def main() -> None:
    s = read_session(SESSION)
    ref = s.reference
    idx = range(300, 420)
    t0 = time.perf_counter()
    frames = [s.frame(i) for i in idx]
    decode = (time.perf_counter() - t0) / len(frames)
    sigma = noise_level(frames[0], ref)
    t0 = time.perf_counter()
    area = [int(contact_mask(f, ref, sigma=sigma).sum()) for f in frames]
    mask = (time.perf_counter() - t0) / len(frames)
    h, w = ref.shape[:2]
    print(f"{len(frames)} frames {w} x {h} of {SESSION.name} (presses among them: "
          f"{sum(a >= 200 for a in area)})")
    print(f"decode {1e3 * decode:.2f} ms a frame; contact_mask {1e3 * mask:.2f} ms a frame, "
          f"{mask / decode:.1f} x the decode")


if __name__ == "__main__":
    main()
