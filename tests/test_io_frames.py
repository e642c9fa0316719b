"""Frame folders, reference frames and ball-press sets (``tactilevision.io``)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from _data import render_reference, synthetic_presses

from tactilevision import InputError
from tactilevision.io import (
    find_reference,
    list_frames,
    read_ball_presses,
    read_frame,
    read_image,
    read_reference,
    taxim_datapack,
)

SHAPE = (48, 64)


def write(path: Path, img: np.ndarray) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    assert cv2.imwrite(str(path), img)
    return path


def frame(value: int, shape=SHAPE) -> np.ndarray:
    img = np.zeros((*shape, 3), np.uint8)
    img[..., 0] = value
    img[..., 1] = 255 - value
    img[..., 2] = np.arange(shape[1], dtype=np.uint8)[None, :]
    return img


# -------------------------------------------------------------- read_image
def test_read_image_bgr_round_trip(tmp_path):
    img = frame(30)
    got = read_image(write(tmp_path / "a.png", img))
    assert got.dtype == np.uint8 and got.shape == (*SHAPE, 3)
    np.testing.assert_array_equal(got, img)  # PNG is lossless and BGR order is kept


def test_read_image_grey_file_gives_three_channels(tmp_path):
    path = write(tmp_path / "grey.png", np.full(SHAPE, 77, np.uint8))
    got = read_image(path)
    assert got.shape == (*SHAPE, 3)
    assert np.all(got == 77)


def test_read_image_missing(tmp_path):
    with pytest.raises(InputError, match=r"missing\.png.*does not exist"):
        read_image(tmp_path / "missing.png")


def test_read_image_unreadable(tmp_path):
    path = tmp_path / "broken.png"
    path.write_bytes(b"this is not a PNG")
    with pytest.raises(InputError, match=r"broken\.png.*not a readable image"):
        read_image(path)


@pytest.mark.parametrize("ext", [".png", ".jpg"])
def test_read_image_refuses_huge_frames_from_the_header(tmp_path, ext):
    """An 8000 x 6000 frame (48 megapixels) is refused naming the file and its size, from
    the header, before it is decoded; the sensors' own sizes pass, and the header reader
    gives the decoder's width and height."""
    from tactilevision.io import MAX_IMAGE_PIXELS
    from tactilevision.io._frames import _header_size

    big = tmp_path / f"huge{ext}"
    cv2.imwrite(str(big), np.zeros((6000, 8000, 3), np.uint8))
    with pytest.raises(InputError, match=r"huge.* is 8000 x 6000 px \(48.0 megapixels\)"):
        read_image(big)
    assert 8000 * 6000 > MAX_IMAGE_PIXELS >= 3280 * 2464          # GelSight Mini passes
    for h, w in ((480, 640), (320, 427), (2464, 3280)):
        ok = tmp_path / f"ok{ext}"
        cv2.imwrite(str(ok), np.full((h, w, 3), 90, np.uint8))
        assert _header_size(ok.read_bytes()) == (w, h)
        assert read_image(ok).shape == (h, w, 3)


def test_read_reference_size_checked(tmp_path):
    path = write(tmp_path / "reference.png", frame(10))
    assert read_reference(path, SHAPE).shape == (*SHAPE, 3)
    with pytest.raises(InputError, match=r"reference\.png.*64 x 48.*expects 65 x 48"):
        read_reference(path, (48, 65))


# ------------------------------------------------------------- list_frames
def test_list_frames_natural_order_and_reference_excluded(tmp_path):
    for name in ["frame_10.png", "frame_2.png", "Frame_3.JPG", "frame_1.jpeg", "frame_100.png",
                 "reference.png", "ref.jpg", "Reference.PNG", "background.png",
                 "Background.jpg"]:
        write(tmp_path / name, frame(5))
    (tmp_path / "notes.txt").write_text("not a frame")
    (tmp_path / "sub").mkdir()
    names = [p.name for p in list_frames(tmp_path)]
    # numbers compared as numbers, case ignored, references and non-images out
    assert names == ["frame_1.jpeg", "frame_2.png", "Frame_3.JPG", "frame_10.png",
                     "frame_100.png"]


def test_list_frames_missing_folder(tmp_path):
    with pytest.raises(InputError, match=r"frames folder .*nowhere does not exist"):
        list_frames(tmp_path / "nowhere")


def test_list_frames_empty_folder(tmp_path):
    write(tmp_path / "reference.png", frame(1))  # a reference alone is no frame
    with pytest.raises(InputError, match=f"{tmp_path.name}.*holds no .png or .jpg frames"):
        list_frames(tmp_path)


# ----------------------------------------------------------- find_reference
def test_find_reference_in_folder_then_parent(tmp_path):
    frames = tmp_path / "session" / "frames"
    write(frames / "f_1.png", frame(1))
    assert find_reference(frames) is None
    parent_ref = write(tmp_path / "session" / "reference.png", frame(2))
    assert find_reference(frames) == parent_ref  # session layout: beside frames/
    own = write(frames / "ref.jpg", frame(3))
    assert find_reference(frames) == own  # the folder's own wins
    pref = write(frames / "reference.png", frame(4))
    assert find_reference(frames) == pref  # reference.png before ref.jpg


def test_find_reference_reads_gs_sdk_background(tmp_path):
    """gs_sdk names the no-contact frame background.png: found, never a frame, and last
    in line behind our own names."""
    bg = write(tmp_path / "background.png", frame(1))
    write(tmp_path / "press_1.png", frame(2))
    assert find_reference(tmp_path) == bg
    assert [p.name for p in list_frames(tmp_path)] == ["press_1.png"]
    ref = write(tmp_path / "ref.jpg", frame(3))
    assert find_reference(tmp_path) == ref


# -------------------------------------------------------- ball presses: dir
def press_folder(folder: Path, n: int = 3, circles: str | None = None) -> tuple:
    ref, frames, centres, radii = synthetic_presses(n, shape=SHAPE, ball_radius=12.0)
    write(folder / "reference.png", ref)
    names = [f"press_{i + 1}.png" for i in range(n)]
    for name, f in zip(names, frames, strict=True):
        write(folder / name, f)
    if circles is not None:
        (folder / "circles.csv").write_text(circles)
    return ref, frames, centres, radii, names


def test_read_ball_presses_folder_without_circles(tmp_path):
    ref, frames, _, _, names = press_folder(tmp_path)
    ps = read_ball_presses(tmp_path)
    np.testing.assert_array_equal(ps.reference, ref)
    np.testing.assert_array_equal(ps.frames, frames)
    assert ps.names == names
    assert ps.centers_px is None and ps.radii_px is None


def test_read_ball_presses_folder_with_circles(tmp_path):
    # rows in any order; matched to frames by name
    text = ("frame,x_px,y_px,radius_px\n"
            "press_3.png,30.5,20.25,7\n"
            "press_1.png,10,11,5.5\n"
            "press_2.png,20,21.5,6\n")
    press_folder(tmp_path, circles=text)
    ps = read_ball_presses(tmp_path)
    assert ps.centers_px.dtype == np.float64
    np.testing.assert_array_equal(ps.centers_px, [[10, 11], [20, 21.5], [30.5, 20.25]])
    np.testing.assert_array_equal(ps.radii_px, [5.5, 6, 7])


def test_circles_bad_line_named(tmp_path):
    text = ("frame,x_px,y_px,radius_px\n"
            "press_1.png,10,11,5.5\n"
            "press_2.png,20,abc,6\n"
            "press_3.png,30,20,7\n")
    press_folder(tmp_path, circles=text)
    with pytest.raises(InputError, match=r"circles\.csv line 3: non-numeric"):
        read_ball_presses(tmp_path)


def test_circles_short_line_named(tmp_path):
    text = "frame,x_px,y_px,radius_px\npress_1.png,10,11,5\npress_2.png,20\n"
    press_folder(tmp_path, circles=text)
    with pytest.raises(InputError, match="line 3"):
        read_ball_presses(tmp_path)


def test_circles_missing_columns(tmp_path):
    press_folder(tmp_path, circles="frame,x,y,r\npress_1.png,1,2,3\n")
    with pytest.raises(InputError, match="frame,x_px,y_px,radius_px"):
        read_ball_presses(tmp_path)


def test_circles_missing_frame(tmp_path):
    text = "frame,x_px,y_px,radius_px\npress_1.png,10,11,5\npress_3.png,10,11,5\n"
    press_folder(tmp_path, circles=text)
    with pytest.raises(InputError, match=r"no circle for frame press_2\.png"):
        read_ball_presses(tmp_path)


def test_ball_press_frame_size_mismatch_names_file(tmp_path):
    press_folder(tmp_path)
    write(tmp_path / "press_9.png", frame(3, shape=(SHAPE[0], SHAPE[1] + 2)))
    with pytest.raises(InputError, match=r"press_9\.png is 66 x 48 px but the reference is "
                       r"64 x 48 px"):
        read_ball_presses(tmp_path)


def test_ball_press_folder_without_reference(tmp_path):
    write(tmp_path / "press_1.png", frame(3))
    with pytest.raises(InputError, match=f"{tmp_path.name} has no reference"):
        read_ball_presses(tmp_path)


def test_ball_presses_neither_file_nor_folder(tmp_path):
    with pytest.raises(InputError, match=r"presses\.zip is neither"):
        read_ball_presses(tmp_path / "presses.zip")


# -------------------------------------------------------- ball presses: npz
def test_read_ball_presses_own_npz(tmp_path):
    ref, frames, centres, radii = synthetic_presses(3, shape=SHAPE, ball_radius=12.0)
    path = tmp_path / "own.npz"
    np.savez(path, reference=ref, frames=frames, centers_px=centres.astype(np.float32),
             radii_px=radii)
    ps = read_ball_presses(path)
    np.testing.assert_array_equal(ps.frames, frames)
    np.testing.assert_array_equal(ps.reference, ref)
    assert ps.centers_px.dtype == np.float64
    np.testing.assert_allclose(ps.centers_px, centres, rtol=1e-6)
    np.testing.assert_array_equal(ps.radii_px, radii)
    assert ps.names == ["press_0", "press_1", "press_2"]
    np.savez(path, reference=ref, frames=frames)  # circles optional
    ps = read_ball_presses(path)
    assert ps.centers_px is None and ps.radii_px is None


def test_read_ball_presses_taxim_layout(tmp_path):
    ref, frames, centres, radii = synthetic_presses(2, shape=SHAPE, ball_radius=12.0)
    path = tmp_path / "dataPack.npz"
    np.savez(path, f0=ref, imgs=frames, touch_center=centres.round().astype(np.int64),
             touch_radius=radii.round().astype(np.int64))
    ps = read_ball_presses(path)
    np.testing.assert_array_equal(ps.frames, frames)
    np.testing.assert_array_equal(ps.centers_px, centres.round())
    assert ps.radii_px.dtype == np.float64


def test_read_real_taxim_datapack(taxim_presses):
    # the data pack as taxim documents it: 48 presses, 480 x 640 BGR
    assert taxim_datapack().name == "dataPack.npz"
    ps = taxim_presses
    assert ps.reference.shape == (480, 640, 3) and ps.reference.dtype == np.uint8
    assert ps.frames.shape == (48, 480, 640, 3)
    assert ps.centers_px.shape == (48, 2) and ps.radii_px.shape == (48,)
    # annotated centres lie in the image (x = column < 640, y = row < 480)
    assert np.all((ps.centers_px >= 0) & (ps.centers_px < [640, 480]))


def test_npz_wrong_keys_named(tmp_path):
    path = tmp_path / "bad.npz"
    np.savez(path, ref=render_reference(SHAPE), imgs_=np.zeros((1, *SHAPE, 3), np.uint8))
    with pytest.raises(InputError) as exc:
        read_ball_presses(path)
    msg = str(exc.value)
    assert "bad.npz" in msg and "'reference'" in msg and "'frames'" in msg
    assert "['imgs_', 'ref']" in msg  # what it has


def test_npz_frames_not_matching_reference(tmp_path):
    path = tmp_path / "mismatch.npz"
    np.savez(path, reference=render_reference(SHAPE),
             frames=np.zeros((2, SHAPE[0], SHAPE[1] + 1, 3), np.uint8))
    with pytest.raises(InputError, match=r"mismatch\.npz: frames"):
        read_ball_presses(path)
    np.savez(path, reference=render_reference(SHAPE).astype(np.float32),
             frames=np.zeros((2, *SHAPE, 3), np.uint8))
    with pytest.raises(InputError, match="uint8"):
        read_ball_presses(path)


def test_npz_missing_or_unreadable(tmp_path):
    with pytest.raises(InputError, match=r"gone\.npz does not exist"):
        read_ball_presses(tmp_path / "gone.npz")
    path = tmp_path / "junk.npz"
    path.write_text("junk")
    with pytest.raises(InputError, match=r"junk\.npz is not a readable \.npz"):
        read_ball_presses(path)


def test_taxim_datapack_unknown_sensor():
    with pytest.raises(InputError, match="no-such-sensor"):
        taxim_datapack("no-such-sensor")


def test_read_frame_checks_the_calibration_size(tmp_path):
    p = write(tmp_path / "f.png", np.zeros((*SHAPE, 3), np.uint8))
    assert read_frame(p, SHAPE).shape == (*SHAPE, 3)
    with pytest.raises(InputError, match=r"frame .*f\.png is 64 x 48 px but the calibration "
                                         r"expects 32 x 24 px"):
        read_frame(p, (24, 32))
    with pytest.raises(InputError, match=r"^reference .*f\.png is 64 x 48 px"):
        read_reference(p, (24, 32))


def test_truncated_images_are_named(tmp_path):
    img = frame(30)
    for suffix in (".jpg", ".png"):
        path = write(tmp_path / f"whole{suffix}", img)
        data = path.read_bytes()
        cut = tmp_path / f"cut{suffix}"
        cut.write_bytes(data[: int(0.7 * len(data))])
        with pytest.raises(InputError, match=rf"cut\{suffix} is a truncated"):
            read_image(cut)
        assert read_image(path).shape == (*SHAPE, 3)      # the whole file still reads


def test_grey_16_bit_and_alpha_frames(tmp_path):
    grey = write(tmp_path / "grey.png", np.full(SHAPE, 77, np.uint8))
    with pytest.raises(InputError, match=r"grey\.png is grey-level"):
        read_frame(grey)
    deep = tmp_path / "deep.png"
    cv2.imwrite(str(deep), np.full((*SHAPE, 3), 40000, np.uint16))
    with pytest.raises(InputError, match=r"deep\.png has 16-bit values"):
        read_image(deep)
    alpha = tmp_path / "alpha.png"
    img = frame(30)
    cv2.imwrite(str(alpha), np.dstack([img, np.full(SHAPE, 255, np.uint8)]))
    np.testing.assert_array_equal(read_frame(alpha), img)


def test_list_frames_of_a_session_folder_reads_its_frames_subfolder(tmp_path):
    """A session folder (reference.png beside frames/) gives the frames of frames/, and the
    reference beside them is found: `reconstruct SESSION` works as `reconstruct SESSION/frames`.
    A folder with frames of its own keeps them, whatever subfolders it has."""
    from tactilevision.io import find_reference

    write(tmp_path / "reference.png", frame(1))
    (tmp_path / "frames").mkdir()
    for name in ("b_2.png", "b_10.png"):
        write(tmp_path / "frames" / name, frame(5))
    assert [p.name for p in list_frames(tmp_path)] == ["b_2.png", "b_10.png"]
    assert find_reference(tmp_path) == tmp_path / "reference.png"
    write(tmp_path / "own.png", frame(3))
    assert [p.name for p in list_frames(tmp_path)] == ["own.png"]
    empty = tmp_path / "empty"
    (empty / "frames").mkdir(parents=True)
    with pytest.raises(InputError, match=r"frames.*holds no .png or .jpg frames"):
        list_frames(empty)
