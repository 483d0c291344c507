"""Photometric weights of linear RGB (lbl_illum.photometry) against colour-science."""

import subprocess
import sys

import numpy as np

from lbl_illum.photometry import luminance, luminance_weights


def test_weights_are_colour_sciences_bt709_row_bit_for_bit():
    import colour

    theirs = np.asarray(colour.RGB_COLOURSPACES["ITU-R BT.709"].matrix_RGB_to_XYZ[1], dtype=np.float64)
    assert luminance_weights().tolist() == theirs.tolist()


def test_white_has_its_own_luminance_and_colour_science_is_not_imported():
    assert abs(luminance_weights().sum() - 1.0) < 1e-15          # Y of the white point is 1
    assert np.allclose(luminance(np.array([[250.0, 250.0, 250.0]])), [250.0], rtol=1e-15)
    code = "import sys; from lbl_illum.photometry import luminance_weights; luminance_weights(); print('colour' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
