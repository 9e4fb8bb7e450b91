"""preview: the same image as `splash preview`, as an (H, W, 3) uint8 array."""

import struct
import subprocess
import zlib

import numpy as np
import pytest

import splash_sph
from conftest import FRAME, FRAME_SPACING


def decode_png(data):
    """An 8-bit RGB PNG's pixels, with zlib only (filters undone by hand)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, width, height = 8, b"", 0, 0
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            width, height = struct.unpack(">II", body[:8])
            assert body[8:10] == b"\x08\x02"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * 3
    out = np.zeros((height, stride), dtype=np.int32)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = np.frombuffer(raw, np.uint8, stride, y * (stride + 1) + 1).astype(np.int32)
        prev = out[y - 1] if y else np.zeros(stride, np.int32)
        if f == 0:
            out[y] = line
        elif f == 2:
            out[y] = (line + prev) % 256
        else:
            cur = np.zeros(stride, np.int32)
            for x in range(stride):
                a = cur[x - 3] if x >= 3 else 0
                b = prev[x]
                c = prev[x - 3] if x >= 3 else 0
                if f == 1:
                    p = a
                elif f == 3:
                    p = (a + b) // 2
                else:
                    pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                    p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                cur[x] = (line[x] + p) % 256
            out[y] = cur
    return out.reshape(height, width, 3).astype(np.uint8)


def test_preview_is_the_cli_image(frame, splash_bin, tmp_path):
    image = splash_sph.preview(frame.positions, spacing=FRAME_SPACING, size=(64, 40), threads=2)
    assert image.shape == (40, 64, 3) and image.dtype == np.uint8
    out = tmp_path / "f.png"
    subprocess.run(
        [str(splash_bin), "preview", str(FRAME), "--spacing", str(FRAME_SPACING),
         "--size", "64x40", "-q", "-o", str(out)],
        check=True,
    )
    np.testing.assert_array_equal(decode_png(out.read_bytes()), image)
    # The fluid is drawn, and the background is left around it.
    background = np.array([0xEC, 0xEE, 0xF2], np.uint8)
    drawn = (image != background).any(axis=2).mean()
    assert 0.05 < drawn < 0.9


def test_bad_cameras_raise(frame):
    p = frame.positions
    with pytest.raises(ValueError, match="field of view"):
        splash_sph.preview(p, spacing=FRAME_SPACING, size=(8, 8), camera=(0, 0, 3), fov=0)
    with pytest.raises(ValueError, match="too large"):
        splash_sph.preview(p, spacing=FRAME_SPACING, size=(100000, 100000))
    with pytest.raises(ValueError, match="coincide"):
        splash_sph.preview(p, spacing=FRAME_SPACING, size=(8, 8), camera=(1, 1, 1), look_at=(1, 1, 1))
    with pytest.raises(ValueError, match="spacing"):
        splash_sph.preview(p, size=(8, 8))


def test_samples_occlusion_and_colours_are_the_cli_image(frame, splash_bin, tmp_path):
    # 4 stratified samples, 4 occlusion rays, coloured by |v| with its legend: the CLI's
    # image for the same flags, on any thread count; each setting changes the picture.
    args = dict(spacing=FRAME_SPACING, size=(64, 40))
    velocity = frame["velocity"]
    image = splash_sph.preview(frame.positions, **args, samples=4, ao=4, values=velocity, threads=2)
    one = splash_sph.preview(frame.positions, **args, samples=4, ao=4, values=velocity, threads=1)
    np.testing.assert_array_equal(image, one)
    out = tmp_path / "f.png"
    subprocess.run(
        [str(splash_bin), "preview", str(FRAME), "--spacing", str(FRAME_SPACING),
         "--size", "64x40", "--samples", "4", "--ao", "4", "--color-by", "velocity",
         "-q", "-o", str(out)],
        check=True,
    )
    np.testing.assert_array_equal(decode_png(out.read_bytes()), image)
    plain = splash_sph.preview(frame.positions, **args)
    variants = [
        splash_sph.preview(frame.positions, **args, samples=4),
        splash_sph.preview(frame.positions, **args, ao=4),
        splash_sph.preview(frame.positions, **args, values=velocity, legend=False),
    ]
    for k, variant in enumerate(variants):
        assert (variant != plain).any(), k
    # The legend, where the image has room for it (not at 64 x 40).
    wide = dict(spacing=FRAME_SPACING, size=(160, 90), values=velocity)
    legend = splash_sph.preview(frame.positions, **wide)
    assert (legend != splash_sph.preview(frame.positions, **wide, legend=False)).any()


def test_values_must_have_one_entry_per_particle(frame):
    with pytest.raises(ValueError):
        splash_sph.preview(frame.positions, spacing=FRAME_SPACING, size=(8, 8),
                           values=np.zeros(len(frame.positions) - 1, np.float32))
