"""Optional dependencies (lbl_illum.optional): one guard, checked before any work."""

import sys

import numpy as np
import pytest

from lbl_illum import optional
from lbl_illum.errors import InputError


def test_check_and_require_say_what_needs_the_package_and_how_to_install_it(monkeypatch):
    monkeypatch.setattr(optional, "available", lambda module: False)
    with pytest.raises(InputError, match=r"^--falsecolor f.png needs matplotlib; install it with pip install "
                                         r"'lbl_illum\[plots\]'$"):
        optional.check("matplotlib", "--falsecolor f.png")
    with pytest.raises(InputError, match=r"^pyvista is needed for 3-D views; install it with pip install "
                                         r"'lbl_illum\[view\]'$"):
        optional.check("pyvista")
    monkeypatch.setitem(sys.modules, "pvlib", None)            # an import that fails
    with pytest.raises(InputError, match=r"needs pvlib; install it with pip install 'lbl_illum\[solar\]'$"):
        optional.require("pvlib", "solar position 'pvlib'")


def test_available_does_not_import():
    assert optional.available("numpy") and not optional.available("no_such_package_here")
    assert not optional.available("")


def test_every_extra_names_a_package_of_pyproject():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "pyproject.toml").read_text()
    for module, (pip, _) in optional.EXTRAS.items():
        extra = pip.strip("'").partition("[")[2].rstrip("]")
        assert (f"{extra} = [" in text) if extra else (f'"{pip}' in text), module


def test_png_previews_need_no_pillow(tmp_path, monkeypatch):
    """PNGs go through OpenImageIO: with Pillow unimportable a preview is still written,
    and read back it has the pixels written."""
    import OpenImageIO as oiio

    from lbl_illum.io.images import write_png

    monkeypatch.setitem(sys.modules, "PIL", None)
    pixels = np.arange(4 * 5 * 3, dtype=np.uint8).reshape(4, 5, 3)
    path = write_png(tmp_path / "p.png", pixels, "a test")
    image = oiio.ImageInput.open(str(path))
    try:
        back = image.read_image(format="uint8")
        description = image.spec().get_string_attribute("ImageDescription")
    finally:
        image.close()
    np.testing.assert_array_equal(back, pixels)
    assert description == "a test"
    assert [p.name for p in tmp_path.iterdir()] == ["p.png"]
