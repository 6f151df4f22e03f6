"""vcm.read / vcm.write round trips and vcm.compare's metrics on known arrays."""

import numpy as np
import pytest

import vcm


def gradient():
    y, x = np.mgrid[0:6, 0:9].astype(np.float32)
    return np.stack([0.1 * x, 0.25 * y, 0.5 + 0.05 * (x + y)], axis=-1).astype(np.float32)


@pytest.mark.parametrize("extension", ["exr", "pfm"])
def test_linear_formats_round_trip_exactly(tmp_path, extension):
    image = gradient()
    image[0, 0] = [1e-8, 1234.5, 3.0]
    path = tmp_path / f"a.{extension}"
    vcm.write(path, image)
    back = vcm.read(path)
    assert back.dtype == np.float32 and back.shape == (6, 9, 3)
    assert np.array_equal(back, image)
    assert back[0, 0, 1] == np.float32(1234.5) and back[5, 8, 2] == image[5, 8, 2]  # top row first


def test_hdr_and_png_round_trip_within_their_precision(tmp_path):
    image = gradient() * 0.9
    vcm.write(tmp_path / "a.hdr", image)
    hdr = vcm.read(tmp_path / "a.hdr")
    # RGBE: an 8-bit mantissa shared by the pixel's largest channel.
    assert np.all(np.abs(hdr - image) <= image.max(axis=-1, keepdims=True) * 2.0 ** -7)
    vcm.write(tmp_path / "a.png", np.clip(image, 0, 1))
    png = vcm.read(tmp_path / "a.png")
    # 8-bit sRGB: at most about 1.5 % relative for values above 0.05.
    assert png.shape == image.shape
    bright = image > 0.05
    assert np.all(np.abs(png - np.clip(image, 0, 1))[bright] <= 0.015 * image[bright] + 1e-3)


def test_compare_known_numbers(tmp_path):
    a = gradient()
    b = a + np.float32(0.1)
    m = vcm.compare(a, b)
    assert m["pixels"] == 54 and m["non_finite"] == 0
    assert abs(m["rmse"] - 0.1) < 1e-6 and abs(m["mae"] - 0.1) < 1e-6
    expected = np.mean(0.01 / (b.astype(np.float64) ** 2 + 0.01))
    assert abs(m["relmse"] - expected) < 1e-6 * expected
    assert np.allclose(np.array(m["means_b"]) - np.array(m["means_a"]), 0.1, atol=1e-6)
    assert m["z_test"] is None
    # Files work as arguments too, and a NaN pixel is excluded.
    a[2, 3, 0] = np.nan
    vcm.write(tmp_path / "a.exr", a)
    m = vcm.compare(tmp_path / "a.exr", b)
    assert (m["pixels"], m["non_finite"]) == (53, 1)


def test_compare_z_test():
    a = gradient()
    variance = np.full_like(a, 1e-6)
    assert vcm.compare(a, a, variance_a=variance, variance_b=variance)["z_test"]["passed"]
    b = a.copy()
    b[2, 3, 1] -= 0.01
    z = vcm.compare(b, a, variance_a=variance, variance_b=variance)["z_test"]
    assert not z["passed"] and z["failing"] == 1
    assert tuple(z["worst_pixel"]) == (3, 2) and z["worst_channel"] == 1


def test_float64_and_non_contiguous_arrays_are_converted(tmp_path):
    image = gradient().astype(np.float64)[:, ::-1]
    vcm.write(tmp_path / "b.exr", image)
    assert np.array_equal(vcm.read(tmp_path / "b.exr"), image.astype(np.float32))
