"""R and MAE against hand-computed values."""

import math

import numpy as np
import pytest

from hybridship.hsc.scoring import correlation, mean_absolute_error, score


def test_mae_and_r_hand_computed():
    y = [1.0, 2.0, 3.0, 4.0]
    p = [1.0, 3.0, 2.0, 5.0]
    # |errors| = 0, 1, 1, 1
    assert mean_absolute_error(y, p) == pytest.approx(0.75)
    # deviations (-1.5, -0.5, 0.5, 1.5) and (-1.75, 0.25, -0.75, 2.25):
    # sum of products 5.5, sums of squares 5 and 8.75
    assert correlation(y, p) == pytest.approx(5.5 / math.sqrt(5 * 8.75))
    assert score(y, p) == pytest.approx((0.8315218, 0.75), abs=1e-7)


def test_r_is_scale_free_and_signed():
    y = np.array([0.0, 1.0, 2.0])
    assert correlation(y, 3 * y + 7) == pytest.approx(1.0)
    assert correlation(y, -y) == pytest.approx(-1.0)
    assert math.isnan(correlation(y, np.ones(3)))


def test_nonfinite_prediction_scores_nan_and_sizes_checked():
    assert math.isnan(mean_absolute_error([1, 2], [1, np.inf]))
    with pytest.raises(ValueError, match="differ in size: 3 vs 2"):
        score([1, 2, 3], [1, 2])
    # a single prediction would broadcast against every measurement: refused by its size too
    with pytest.raises(ValueError, match="differ in size: 3 vs 1"):
        score([1, 2, 3], [2.0])


def test_nonfinite_measurement_refused():
    with pytest.raises(ValueError, match="^y_true"):
        score([1.0, np.nan, 3.0], [1.0, 2.0, 3.0])


def test_a_single_sample_is_not_scored():
    """R needs at least two samples: one is refused rather than scored."""
    with pytest.raises(ValueError, match="at least two samples"):
        score([1.0], [1.0])


def test_a_transposed_prediction_is_refused_not_scored():
    """Same size, other layout: flattened, (N, 2) against (2, N) paired samples that do not
    belong together and scored R -0.00 for a prediction with R 1.00 (no error). A column
    against a flat series of the same samples is still scored."""
    rng = np.random.default_rng(0)
    y = rng.standard_normal((50, 2))
    p = y + 0.01 * rng.standard_normal((50, 2))
    with pytest.raises(ValueError, match=r"differ in shape: \(50, 2\) vs \(2, 50\)"):
        score(y, p.T)
    assert score(y[:, 0], p[:, :1]) == pytest.approx(score(y[:, 0], p[:, 0]))


@pytest.mark.parametrize("y_true,y_pred,name", [(["1", "2", "3"], [1.0, 2.0, 3.0], "y_true"),
                                                ([1.0, 2.0, 3.0], ["a", "b", "c"], "y_pred"),
                                                ({"a": 1}, [1.0], "y_true")])
def test_text_or_a_mapping_is_refused_naming_the_argument(y_true, y_pred, name):
    """Text numbers were scored as numbers ("1" as 1.0) and other text or a dict failed in
    numpy's words ("could not convert string to float"), naming neither argument."""
    with pytest.raises(TypeError, match=f"^{name}: expected an array of real numbers"):
        score(y_true, y_pred)
