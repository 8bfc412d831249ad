"""The CTRNN's sigmoid saturates without a RuntimeWarning (the test suite printed one)."""

import warnings

import numpy as np

from evobiped.controllers.ctrnn import sigmoid


def test_a_very_negative_input_gives_zero_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        y = sigmoid(np.array([-1000.0, -710.0, 0.0, 710.0, 1000.0]))
    assert y[0] == 0.0 and y[1] == 0.0 and y[2] == 0.5 and y[3] == 1.0 and y[4] == 1.0
