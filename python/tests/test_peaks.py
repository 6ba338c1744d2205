"""lasercell.detect_peaks on stripe images: a rendered stripe whose rows are known (8 and 16
bit, strided views read in place), the estimators' formulas recomputed in NumPy, saturated and
ambiguous columns, bad images; and a real green laser line across a chessboard."""

import math
import os

import numpy as np
import pytest

import lasercell


def stripe_image(rows, width=120, height=60, sigma=1.5, amplitude=180.0, background=12.0):
    """Each column integrates a Gaussian line over the pixel (the way a sensor pixel collects
    light), not the point-sampled profile the Gaussian estimator would fit exactly."""
    edges = np.arange(height + 1)[:, None] - 0.5
    cdf = np.vectorize(lambda z: 0.5 * (1.0 + math.erf(z / (sigma * math.sqrt(2.0)))))
    light = np.diff(cdf(edges - rows[None, :]), axis=0) * amplitude * sigma * math.sqrt(2 * math.pi)
    return light + background


def truth_rows(width=120):
    return 20.0 + 0.137 * np.arange(width) + 2.0 * np.sin(np.arange(width) / 9.0)


def gaussian_three_point(image, result):
    """Fisher & Naidu's Gaussian estimator: a parabola through the logarithms of the top sample
    and its neighbours, on the samples above the column's background."""
    rows = np.full(image.shape[1], np.nan)
    for c in range(image.shape[1]):
        if result.status[c] != 1:
            continue
        f = image[:, c].astype(float) - result.background[c]
        top = int(np.argmax(f))
        if top == 0 or top == len(f) - 1 or min(f[top - 1:top + 2]) <= 0:
            continue
        a, b, d = np.log(f[top - 1:top + 2])
        rows[c] = top + 0.5 * (a - d) / (a - 2 * b + d)
    return rows


def test_rows_of_a_rendered_stripe():
    truth = truth_rows()
    image = np.round(stripe_image(truth)).astype(np.uint8)
    result = lasercell.detect_peaks(image)
    assert result.valid == image.shape[1] and result.row_px.dtype == np.float32
    assert np.max(np.abs(result.row_px - truth)) < 0.06  # rounding to 8 bit and pixel integration
    np.testing.assert_allclose(result.row_px, gaussian_three_point(image, result), atol=2e-4)
    for estimator in ("cog", "blais-rioux"):
        other = lasercell.detect_peaks(image, estimator=estimator)
        assert other.valid == image.shape[1]
        assert np.max(np.abs(other.row_px - truth)) < 0.1, estimator
    assert "120 columns" in result.summary()


def test_sixteen_bit_and_strided_images_are_read_in_place():
    truth = truth_rows()
    image8 = np.round(stripe_image(truth)).astype(np.uint8)
    image16 = image8.astype(np.uint16) * 257
    r8 = lasercell.detect_peaks(image8)
    r16 = lasercell.detect_peaks(image16, min_height=20.0 * 257)
    np.testing.assert_allclose(r16.row_px, r8.row_px, atol=1e-5)
    every_other = np.round(stripe_image(truth, height=120)).astype(np.uint8)[::2]
    assert not every_other.flags.c_contiguous
    np.testing.assert_array_equal(lasercell.detect_peaks(every_other).row_px,
                                  lasercell.detect_peaks(np.ascontiguousarray(every_other)).row_px)
    transposed = lasercell.detect_peaks(np.ascontiguousarray(image8.T), peaks_per_row=True)
    np.testing.assert_array_equal(transposed.row_px, r8.row_px)


def test_saturated_and_ambiguous_columns_are_reported():
    saturated = stripe_image(np.full(40, 20.0), width=40, amplitude=400.0)  # clipped at 255
    double = (stripe_image(np.full(40, 20.0), width=40, amplitude=150.0)
              + stripe_image(np.full(40, 45.0), width=40, amplitude=120.0) - 12.0)
    image = np.where(np.arange(40)[None, :] < 30, saturated, double)
    image = np.clip(np.round(image), 0, 255).astype(np.uint8)
    result = lasercell.detect_peaks(image)
    assert result.saturated + result.ambiguous == 40
    assert set(result.status[:30]) == {2} and set(result.status[30:]) == {3}
    rejected = lasercell.detect_peaks(image, reject_saturated=True, reject_ambiguous=True)
    assert np.all(np.isnan(rejected.row_px))


def test_bad_images_and_options():
    image = np.zeros((10, 10), dtype=np.uint8)
    with pytest.raises(TypeError, match="uint8 or uint16"):
        lasercell.detect_peaks(image.astype(np.float32))
    with pytest.raises(lasercell.InputError, match="image"):
        lasercell.detect_peaks(np.zeros((10, 10, 3), dtype=np.uint8))
    with pytest.raises(lasercell.InputError, match="contiguous"):
        lasercell.detect_peaks(np.asfortranarray(np.zeros((10, 12), dtype=np.uint8)))
    with pytest.raises(lasercell.OptionError, match="estimator|peak estimator"):
        lasercell.detect_peaks(image, estimator="median")
    with pytest.raises(lasercell.OptionError, match="min_height"):
        lasercell.detect_peaks(image, min_height=-1.0)
    assert lasercell.detect_peaks(image).no_peak == 10


def test_a_real_laser_line_across_a_chessboard(shared_data):
    from PIL import Image  # python3-pil, a dependency of python3-matplotlib

    root = shared_data("laser_stripe_chessboard")
    rgb = np.asarray(Image.open(os.path.join(root, "1_right.jpg")).convert("RGB")).astype(int)
    signal = np.clip(rgb[:, :, 1] - rgb[:, :, 0], 0, 255).astype(np.uint8)  # green minus red
    result = lasercell.detect_peaks(signal, peaks_per_row=True)  # the line is vertical
    rows = np.arange(100, 451)
    found = rows[np.isfinite(result.row_px[rows])]
    assert len(found) >= 0.97 * len(rows)
    # On the planar board the line is one smooth curve (a quadratic through the lens'
    # distortion leaves sub-pixel residuals); jumps to checker edges would leave pixels.
    t = (found - 275.0) / 175.0
    x = result.row_px[found].astype(float)
    residual = x - np.polyval(np.polyfit(t, x, 2), t)
    assert np.sqrt(np.mean(residual**2)) < 0.4 and np.max(np.abs(residual)) < 1.5
    clean = found[result.status[found] == 1]
    np.testing.assert_allclose(result.row_px[clean], gaussian_three_point(signal.T, result)[clean],
                               atol=2e-4)
