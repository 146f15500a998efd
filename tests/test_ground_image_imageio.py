import logging

import numpy as np
import pytest
from factories import extraneous_jpeg, garbled_jpeg, jpeg_bytes, smooth_jpeg, write_image
from PIL import Image

from ground.image.imageio import ImageError, check_complete, decode_image, image_size, jpeg_repaired, read_image


def test_rgb_jpeg_reads_as_rgb_uint8(tmp_path):
    path = tmp_path / "a.jpg"
    Image.new("RGB", (30, 20), (250, 10, 10)).save(path, quality=95)
    img = read_image(path)
    assert img.shape == (20, 30, 3) and img.dtype == np.uint8
    r, g, b = img[10, 15]
    assert r > 200 and g < 60 and b < 60  # RGB order, not BGR


@pytest.mark.parametrize("orientation", [6, 8])
def test_exif_rotation_applied_to_pixels_and_size(tmp_path, orientation):
    path = tmp_path / f"rot{orientation}.jpg"
    path.write_bytes(jpeg_bytes(40, 20, orientation=orientation))
    assert image_size(path) == (20, 40)
    assert read_image(path).shape == (40, 20, 3)


def test_16bit_png_scaled_to_8bit(tmp_path):
    path = tmp_path / "deep.png"
    arr = np.full((8, 9), 65535, dtype=np.uint16)
    arr[0, 0] = 0
    Image.fromarray(arr).save(path)
    img = read_image(path)
    assert img.dtype == np.uint8 and img.shape == (8, 9, 3)
    assert img[0, 0].tolist() == [0, 0, 0] and img[4, 4].tolist() == [255, 255, 255]


def test_16bit_colour_png(tmp_path):
    import cv2

    path = tmp_path / "deep_rgb.png"
    bgr = np.zeros((4, 5, 3), dtype=np.uint16)
    bgr[..., 2] = 65535  # red in BGR
    cv2.imwrite(str(path), bgr)
    assert read_image(path)[0, 0].tolist() == [255, 0, 0]


def test_grey_and_rgba_become_rgb(tmp_path):
    grey = tmp_path / "grey.png"
    Image.new("L", (6, 4), 128).save(grey)
    assert read_image(grey)[0, 0].tolist() == [128, 128, 128]
    rgba = tmp_path / "rgba.png"
    Image.new("RGBA", (6, 4), (10, 20, 30, 40)).save(rgba)
    img = read_image(rgba)
    assert img.shape == (4, 6, 3) and img[0, 0].tolist() == [10, 20, 30]


def test_unicode_path(tmp_path):
    path = write_image(tmp_path / "incendie_火灾_ñ" / "фото.png", 12, 7)
    assert image_size(path) == (12, 7)
    assert read_image(path).shape == (7, 12, 3)


def test_gif_falls_back_to_pillow(tmp_path):
    path = tmp_path / "anim.gif"
    Image.new("P", (9, 5), 3).save(path)
    assert read_image(path).shape == (5, 9, 3)


@pytest.mark.parametrize(
    "name,content,reason",
    [
        ("empty.jpg", b"", "empty file"),
        ("text.jpg", b"this is not an image at all", "not"),
        ("trunc.jpg", None, "truncated JPEG"),
        ("trunc.png", None, "truncated PNG"),
    ],
)
def test_bad_files_raise_image_error_with_path_and_reason(tmp_path, name, content, reason):
    path = tmp_path / name
    if content is None:
        good = tmp_path / ("good" + path.suffix)
        write_image(good, 64, 64)
        data = good.read_bytes()
        content = data[: len(data) // 2]
    path.write_bytes(content)
    with pytest.raises(ImageError) as info:
        read_image(path)
    assert str(path) in str(info.value) and reason in info.value.reason


def test_header_errors(tmp_path):
    with pytest.raises(ImageError, match="file not found"):
        image_size(tmp_path / "missing.jpg")
    (tmp_path / "zero.png").write_bytes(b"")
    with pytest.raises(ImageError, match="empty file"):
        image_size(tmp_path / "zero.png")
    (tmp_path / "junk.png").write_bytes(b"\x00" * 100)
    with pytest.raises(ImageError, match="not an image"):
        image_size(tmp_path / "junk.png")


@pytest.mark.parametrize("content", [b"\x00" * 100, b"hello, not an image\n", b"GIF89a" + bytes(20)])
def test_a_message_names_the_file_never_an_in_memory_buffer(tmp_path, content):
    path = tmp_path / "photo.jpg"
    path.write_bytes(content)
    for read in (image_size, read_image, lambda p: decode_image(p.read_bytes(), p)):
        with pytest.raises(ImageError) as info:
            read(path)
        assert str(info.value).startswith(f"{path}: ") and "BytesIO" not in str(info.value), str(info.value)


def test_decode_bytes_matches_file(tmp_path):
    path = write_image(tmp_path / "x.png", 10, 10, seed=3)
    np.testing.assert_array_equal(decode_image(path.read_bytes()), read_image(path))


def _jpeg(tmp_path, w=64, h=48):
    path = write_image(tmp_path / "src.jpg", w, h, seed=5)
    return path.read_bytes()


@pytest.mark.parametrize("extra", [b"\x00" * 25_000, b"trailing metadata written by a tool" * 30, b"\r\n"])
def test_padding_and_trailing_bytes_after_the_end_marker_are_fine(tmp_path, extra):
    data = _jpeg(tmp_path)
    path = tmp_path / "padded.jpg"
    path.write_bytes(data + extra)
    np.testing.assert_array_equal(read_image(path), decode_image(data))
    png = write_image(tmp_path / "x.png", 20, 10, seed=1).read_bytes()
    (tmp_path / "padded.png").write_bytes(png + extra)
    np.testing.assert_array_equal(read_image(tmp_path / "padded.png"), decode_image(png))


def test_end_marker_before_the_scan_does_not_make_a_truncated_jpeg_complete(tmp_path):
    data = _jpeg(tmp_path)
    comment = b"thumbnail \xff\xd9 inside"  # like an EXIF thumbnail's own end marker
    segment = b"\xff\xfe" + (len(comment) + 2).to_bytes(2, "big") + comment
    spliced = data[:2] + segment + data[2:]
    np.testing.assert_array_equal(decode_image(spliced), decode_image(data))  # the comment changes nothing
    with pytest.raises(ImageError, match="truncated JPEG"):
        decode_image(spliced[: len(spliced) * 2 // 3], "cut.jpg")
    with pytest.raises(ImageError, match="ends inside its headers"):
        decode_image(spliced[:40], "cut.jpg")


def test_garbled_scan_data_is_refused_naming_the_file_where_opencv_decodes_grey(tmp_path):
    import cv2

    data = garbled_jpeg()
    grey = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)  # what the user got: no error, grey
    assert grey is not None and (np.abs(grey.astype(int) - 128).max(axis=2) <= 1).mean() > 0.3
    path = tmp_path / "garbled.jpg"
    path.write_bytes(data)
    for read in (read_image, image_size, lambda p: decode_image(p.read_bytes(), p, min_side=16)):
        with pytest.raises(ImageError, match="corrupt JPEG data") as info:
            read(path)
        assert info.value.path == str(path) and "restart marker RST5" in info.value.reason


def test_progressive_and_restart_coded_jpegs_read_and_a_restart_out_of_sequence_is_refused(tmp_path):
    import cv2

    rng = np.random.default_rng(0)
    bgr = cv2.resize(rng.integers(0, 256, (12, 16, 3), dtype=np.uint8), (160, 120), interpolation=cv2.INTER_CUBIC)
    files = {
        "progressive": smooth_jpeg(160, 120, progressive=True),
        "restarts": cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_RST_INTERVAL, 2])[1].tobytes(),
        "both": cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_PROGRESSIVE, 1, cv2.IMWRITE_JPEG_RST_INTERVAL, 1])[1],
        "grey": cv2.imencode(".jpg", bgr[:, :, 0], [cv2.IMWRITE_JPEG_PROGRESSIVE, 1])[1].tobytes(),
    }
    for name, data in files.items():
        assert decode_image(bytes(data), name).shape == (120, 160, 3)
    data = bytearray(files["restarts"])
    rst = data.index(b"\xff\xd3")  # RST3 -> RST6: the decoder resyncs and shifts the blocks after it
    data[rst + 1] = 0xD6
    with pytest.raises(ImageError, match=r"restart marker RST6 at byte \d+: RST3 expected"):
        decode_image(bytes(data), "resync.jpg")


def test_reduced_decoding_keeps_min_side_and_reports_the_full_size(tmp_path):
    from ground.image.imageio import decode_sized

    path = write_image(tmp_path / "big.jpg", 1600, 1200, seed=2)
    data = path.read_bytes()
    full = decode_image(data)
    small, size = decode_sized(data, path, min_side=300)
    assert size == (1600, 1200) and small.shape == (300, 400, 3)  # 1/4: 1200 / 4 = 300 >= 300
    assert decode_sized(data, path, min_side=301)[0].shape == (600, 800, 3)  # 1/2
    assert decode_sized(data, path, min_side=2000)[0].shape == full.shape
    # the DCT-scaled decode is the picture, not something else: close to an area resize of the full decode
    import cv2

    area = cv2.resize(full, (400, 300), interpolation=cv2.INTER_AREA).astype(int)
    assert np.abs(small.astype(int) - area).mean() < 4.0
    png = write_image(tmp_path / "big.png", 800, 600, seed=2)
    assert read_image(png, min_side=100).shape == (600, 800, 3)  # PNG has no reduced decoding


def test_images_over_the_pixel_budget_are_refused(tmp_path, monkeypatch):
    import ground.image.imageio as io_

    path = write_image(tmp_path / "wide.png", 400, 300)
    monkeypatch.setattr(io_, "MAX_PIXELS", 100_000)
    with pytest.raises(ImageError, match=r"400x300 image .* over the 0.1 MP decoding budget"):
        read_image(path)
    jpg = write_image(tmp_path / "wide.jpg", 800, 600)
    assert read_image(jpg, min_side=150).shape == (150, 200, 3)  # decoded at 1/4: 30,000 pixels, within
    with pytest.raises(ImageError, match="decoding budget"):
        read_image(jpg)


def test_unit_to_u8_rounds_to_nearest_and_clips() -> None:
    import numpy as np

    from ground.image.imageio import unit_to_u8

    values = np.array([[-0.5, 0.0, 0.5 / 255, 1.5 / 255], [0.499, 0.5, 1.0, 7.0]], dtype=np.float32)
    out = unit_to_u8(values)
    assert out.dtype == np.uint8 and out.shape == values.shape
    assert out.tolist() == [[0, 0, 0, 2], [127, 128, 255, 255]]  # halves to even, as np.round
    grid = np.linspace(0.0, 1.0, 1001)
    assert np.abs(unit_to_u8(grid).astype(float) - grid * 255.0).max() <= 0.5


@pytest.mark.parametrize(
    ("junk", "before"),
    [(b"\x00", b"\xff\xdb"), (b"\x12\x34\xff\x00\x56", b"\xff\xc0"), (b"\xff\x00", b"\xff\xda")],
    ids=["one-byte-before-dqt", "stuffed-pair-before-sof", "ff00-before-sos"],
)
def test_extraneous_header_bytes_are_named_per_file_with_libjpegs_count(tmp_path, capfd, caplog, junk, before):
    """libjpeg's nameless stderr line becomes a warning naming the file, with libjpeg's own count and marker; the
    pixels are libjpeg's."""
    import re

    import cv2

    clean, bad = extraneous_jpeg(junk, before)
    cv2.imdecode(np.frombuffer(bad, np.uint8), cv2.IMREAD_COLOR)  # libjpeg's words, on fd 2
    said = re.search(r"Corrupt JPEG data: (\d+) extraneous bytes before marker (0x[0-9a-f]{2})", capfd.readouterr().err)
    assert said is not None
    path = tmp_path / "bad.jpg"
    path.write_bytes(bad)
    with caplog.at_level(logging.WARNING, logger="ground.image.imageio"):
        image = read_image(path)
    np.testing.assert_array_equal(image, decode_image(clean))  # what libjpeg decodes from the file, too
    assert "Corrupt JPEG" not in capfd.readouterr().err  # libjpeg never saw the bytes: no nameless line
    assert [r.getMessage() for r in caplog.records] == [
        f"{path}: corrupt JPEG data ({said[1]} extraneous bytes before marker {said[2]})"
    ]
    assert jpeg_repaired(clean) == (clean, []) and jpeg_repaired(bad)[0] == clean
    check_complete(bad, path)  # complete: only the headers hold the bytes


def test_decoding_threads_name_each_file_they_decode(tmp_path, caplog):
    from concurrent.futures import ThreadPoolExecutor

    paths = []
    for k in range(8):
        clean, bad = extraneous_jpeg(b"\x00" * (k % 3), seed=k)
        paths.append(tmp_path / f"f{k}.jpg")
        paths[-1].write_bytes(bad)
    with caplog.at_level(logging.WARNING, logger="ground.image.imageio"), ThreadPoolExecutor(4) as pool:
        list(pool.map(read_image, paths * 4))
    named = {r.getMessage() for r in caplog.records}
    assert named == {f"{p}: corrupt JPEG data ({k % 3} extraneous bytes before marker 0xdb)"
                     for k, p in enumerate(paths) if k % 3}  # fmt: skip
