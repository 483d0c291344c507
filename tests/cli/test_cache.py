"""``lbl-illum cache info`` and ``cache merge``: the header and level statistics of a cache
file, the union of compatible files, and one-line refusals without output."""

import json

import numpy as np
import pytest

from lbl_illum import Integrator, Options
from lbl_illum.cli.main import main
from lbl_illum.io.cachefile import read_cache_file

from conftest import CACHE_OPTIONS

OPTS = Options(**CACHE_OPTIONS)


def cache_cli(argv, capsys):
    """Run ``lbl-illum ARGV``: (exit status, standard output, standard error)."""
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def record_set(data, k: int) -> set:
    """The (position, normal) pairs of level k of a cache file's records, as bytes."""
    a = data.level(k)
    return {(p.tobytes(), n.tobytes()) for p, n in zip(a["P"], a["N"])}


def test_cache_info_prints_header_and_level_statistics(office_cache, capsys):
    path, integ = office_cache
    code, out, err = cache_cli(["cache", "info", str(path)], capsys)
    assert code == 0, err
    assert "format version 2" in out and integ.fingerprint in out
    assert "accuracy 0.2, bounces 2, samples 128" in out and "cie-overcast" in out
    counts = integ.cache.record_counts
    assert f"records: {sum(counts):,} in 3 levels" in out
    code, out, err = cache_cli(["cache", "info", "--json", str(path)], capsys)
    doc = json.loads(out)
    assert [lv["records"] for lv in doc["levels"]] == counts
    lv = integ.cache.levels[1]
    R = lv.R[:lv.count].astype(np.float64)
    assert doc["levels"][1]["radius"]["q50"] == pytest.approx(np.median(R))
    assert doc["levels"][1]["radius"]["q0"] == pytest.approx(R.min())
    from lbl_illum.photometry import luminance
    E = luminance(lv.E[:lv.count].astype(np.float64))
    assert doc["levels"][1]["illuminance"]["max"] == pytest.approx(E.max())
    assert doc["memory_bytes"] > 100 * sum(counts)


def test_cache_merge_command(office_quarter, office_cache, tmp_path, capsys):
    path, integ = office_cache
    scene, points, normals = office_quarter
    extra = Integrator(scene, OPTS)
    extra.compute(points[:5] + [0.31, 0.17, 0.0], normals[:5])
    other_path = tmp_path / "other.lblcache"
    extra.cache.save(other_path)
    out_path = tmp_path / "merged.lblcache"
    code, out, err = cache_cli(["cache", "merge", str(path), str(other_path), "-o", str(out_path)], capsys)
    assert code == 0, err
    merged = read_cache_file(out_path)
    for k in range(3):
        assert record_set(merged, k) == record_set(read_cache_file(path), k) | record_set(extra.cache.to_data(), k)
    assert err.startswith("lbl-illum: cache merge: 2 files") and err.count("\n") == 1
    # incompatible caches: one line, exit status 2, no output
    wrong = Integrator(scene, OPTS.replace(samples=64))
    wrong.compute(points[:2], normals[:2])
    wrong_path = tmp_path / "wrong.lblcache"
    wrong.cache.save(wrong_path)
    code, out, err = cache_cli(["cache", "merge", str(path), str(wrong_path), "-o", str(tmp_path / "no.lblcache")],
                               capsys)
    assert code == 2 and err.count("\n") == 1 and "samples differ" in err
    assert not (tmp_path / "no.lblcache").exists()
    code, out, err = cache_cli(["cache", "info", str(tmp_path / "missing.lblcache")], capsys)
    assert code == 2 and "no such cache file" in err and err.count("\n") == 1
    code, out, err = cache_cli(["cache", "merge", str(path)], capsys)      # -o is required
    assert code == 2 and err.count("\n") == 1


def test_cache_info_help_prints_percent_signs_once(capsys):
    from lbl_illum.cli.main import main

    with pytest.raises(SystemExit):
        main(["cache", "info", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "(min, 10%, median, 90%, max)" in out and "%%" not in out
