"""File and folder I/O: frame folders, ball-press sets, measurement tables.

Everything that touches the file system lives here (and in ``cli``); the
modules under ``optics``, ``mechanics`` and ``fem`` work on arrays.
"""

# frames and ball presses (optics)
from ._frames import (
    MAX_IMAGE_PIXELS,
    BallPressSet,
    find_reference,
    list_frames,
    read_ball_presses,
    read_frame,
    read_image,
    read_reference,
    taxim_datapack,
)
from ._gs_sdk import read_gs_sdk

__all__ = ["MAX_IMAGE_PIXELS", "BallPressSet", "find_reference", "list_frames",
           "read_ball_presses", "read_frame", "read_gs_sdk", "read_image", "read_reference",
           "taxim_datapack"]

# measurements tables (mechanics): names appended below
from ._measurements import (
    COLUMN_ORDER,
    REQUIRED_COLUMNS,
    STANDARD_GRAVITY,
    Measurements,
    read_holds,
    read_measurements,
    sidecar_geometry,
    write_measurements,
)

__all__ += ["COLUMN_ORDER", "REQUIRED_COLUMNS", "STANDARD_GRAVITY", "Measurements", "read_holds",
            "read_measurements", "sidecar_geometry", "write_measurements"]

# indentation session folders (calibrate): names appended below
from ._session import (  # noqa: E402
    DEPTH_TOLERANCE_MM,
    KNOWN_KEYS,
    Session,
    SessionConfig,
    read_presses,
    read_session,
)

__all__ += ["DEPTH_TOLERANCE_MM", "KNOWN_KEYS", "Session", "SessionConfig", "read_presses",
            "read_session"]

# the one rule for session.toml keys no reader reads (every reader of a session.toml)
from ._keys import SIDECAR_KEYS, equal_area_radius, unknown_key_notes, warn_unknown_keys  # noqa: E402

__all__ += ["SIDECAR_KEYS", "equal_area_radius", "unknown_key_notes", "warn_unknown_keys"]

# video files (batch, reconstruct): names appended below
from ._video import VIDEO_SUFFIXES, VideoFrames, find_video_reference, is_video  # noqa: E402

__all__ += ["VIDEO_SUFFIXES", "VideoFrames", "find_video_reference", "is_video"]

# output folders written whole or not at all (every command, the pipeline): names appended
from ._output import (  # noqa: E402
    MANIFEST,
    StagedOutput,
    check_output_file,
    check_output_folder,
    check_overwrite,
    output_folder,
    record_output,
    remove_staging,
    write_output_file,
)

__all__ += ["MANIFEST", "StagedOutput", "check_output_file", "check_output_folder",
            "check_overwrite", "output_folder", "record_output", "remove_staging",
            "write_output_file"]

# one way in for frames: folder, video, session or camera (every command): names appended
from ._source import FrameSource, open_source  # noqa: E402

__all__ += ["FrameSource", "open_source"]

# force-depth ramps (mechanics.fit_ramp): names appended below
from ._ramp import Ramp, read_ramp  # noqa: E402

__all__ += ["Ramp", "read_ramp"]

# dead weights: frames of a ball at rest under known masses
from ._dead_weights import DeadWeightSession, read_dead_weights  # noqa: E402

__all__ += ["DeadWeightSession", "read_dead_weights"]
