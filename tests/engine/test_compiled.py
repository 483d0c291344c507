import numpy as np
from numba import prange

from lbl_illum.engine.compiled import serial_and_parallel


def _scaled_sum(x, out):
    for i in prange(x.shape[0]):
        out[i] = 2.0 * x[i] + 1.0


def test_serial_and_parallel_versions_agree_and_are_cached_under_different_names():
    serial, parallel = serial_and_parallel(_scaled_sum)
    x = np.random.default_rng(0).random(5000)
    a, b = np.empty_like(x), np.empty_like(x)
    serial(x, a)
    parallel(x, b)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, 2.0 * x + 1.0)
    assert serial.py_func.__qualname__ != parallel.py_func.__qualname__
    assert not serial.targetoptions.get("parallel") and parallel.targetoptions.get("parallel")
