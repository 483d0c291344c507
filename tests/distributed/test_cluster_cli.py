"""The cluster options of the commands: bad input is one line, exit 2, within seconds,
with nothing written."""

import socket
import time
from pathlib import Path

import pytest

from lbl_illum.cli.main import main
from lbl_illum.distributed import cluster as cluster_module
from lbl_illum import optional

OFFICE = Path(__file__).resolve().parents[2] / "examples" / "office"


def run(argv, capsys):
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


def job(tmp_path, *extra):
    return ["illuminance", OFFICE / "scene.toml", "--points", OFFICE / "grid.pts", "-o", tmp_path / "out.csv",
            "--preset", "draft", "--cache", tmp_path / "c.cache", *extra]


def nothing_written(tmp_path):
    return sorted(p.name for p in tmp_path.iterdir()) == []


def test_unreachable_scheduler_is_one_line_within_seconds(tmp_path, capsys, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(cluster_module, "CONNECT_SECONDS", 1.0)
    with socket.socket() as s:            # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    t0 = time.perf_counter()
    code, err = run(job(tmp_path, "--scheduler", f"tcp://127.0.0.1:{port}"), capsys)
    assert code == 2 and time.perf_counter() - t0 < 10
    assert err.startswith(f"lbl-illum: error: --scheduler tcp://127.0.0.1:{port}: no scheduler answered within 1 s")
    assert err.count("\n") == 1 and nothing_written(tmp_path)


def test_cluster_without_dask_names_the_extra(tmp_path, capsys, monkeypatch):
    real = optional.available
    monkeypatch.setattr(optional, "available", lambda m: False if m == "distributed" else real(m))
    code, err = run(job(tmp_path, "--workers", "2"), capsys)
    assert code == 2 and err == ("lbl-illum: error: --workers/--scheduler needs distributed; install it with "
                                 "pip install 'lbl_illum[distributed]'\n")
    assert nothing_written(tmp_path)


@pytest.mark.parametrize("extra, message", [
    (["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "give either --workers or --scheduler, not both"),
    (["--chunk-size", "100"], "--chunk-size and --round-chunks go with --workers N or --scheduler ADDRESS"),
    (["--scheduler", "nowhere"], "--scheduler nowhere: give the scheduler's address as tcp://HOST:PORT"),
    (["--workers", "-1"], "argument --workers: must be >= 0, got -1"),
])
def test_cluster_options_checked_before_any_work(tmp_path, capsys, extra, message):
    if "nowhere" in extra:
        pytest.importorskip("distributed")
    code, err = run(job(tmp_path, *extra), capsys)
    assert code == 2 and message in err and err.count("\n") == 1
    assert nothing_written(tmp_path)


def test_render_and_daylight_factor_take_the_cluster_options(capsys):
    for command in ("render", "daylight-factor"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "--workers N" in text and "--scheduler ADDRESS" in text and "(default 2048)" in text


def test_user_guide_states_the_cluster_defaults_of_the_code():
    import re

    from lbl_illum.distributed.plan import CHUNK_POINTS, ROUND_CHUNKS

    guide = (Path(__file__).resolve().parents[2] / "docs" / "user-guide.md").read_text()
    for option, value in (("--chunk-size", CHUNK_POINTS), ("--round-chunks", ROUND_CHUNKS)):
        row = re.search(r"^\| `" + re.escape(option) + r"[ `][^|]*\| ([^|]+) \|", guide, flags=re.M)
        assert row and row.group(1).strip() == str(value), (option, row and row.group(1))
