"""Text files as spreadsheets and editors save them (lbl_illum/io/files.py): a UTF-8
byte-order mark at the start is no part of the text."""

import numpy as np

from lbl_illum.io.files import read_text_file
from lbl_illum.io.points import read_points
from lbl_illum.scene import load_scene

BOM = b"\xef\xbb\xbf"


def test_a_byte_order_mark_is_dropped(tmp_path):
    path = tmp_path / "a.txt"
    path.write_bytes(BOM + "x = 1\n".encode())
    assert read_text_file(path) == "x = 1\n"


def test_points_file_saved_with_a_byte_order_mark(tmp_path):
    path = tmp_path / "grid.pts"
    path.write_bytes(BOM + b"0.5 0.5 0.8 0 0 1\n1.5 0.5 0.8 0 0 1\n")
    points, normals = read_points(path, 1.0)
    assert np.array_equal(points, [[0.5, 0.5, 0.8], [1.5, 0.5, 0.8]]) and np.array_equal(normals[:, 2], [1, 1])


def test_scene_file_saved_with_a_byte_order_mark(tmp_path):
    text = ('[[geometry]]\nshape = "rectangle"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\n'
            'material = "m"\n[materials.m]\ntype = "diffuse"\nreflectance = 0.5\n[sky]\ntype = "uniform"\n')
    (tmp_path / "s.toml").write_bytes(BOM + text.encode())
    assert len(load_scene(tmp_path / "s.toml").triangles) == 2
