"""Runs on a Dask ``LocalCluster`` of two workers on the loopback address: the bits of the
run in one process, a worker killed mid-run costing time and not results, and the
checks before any work (a scene a worker cannot read, workers of another version, a
scheduler without workers), each one line."""

import os
import signal
import time

import numpy as np
import pytest

pytest.importorskip("distributed")

from distributed import Client, LocalCluster  # noqa: E402

from lbl_illum.cli.main import main  # noqa: E402
from lbl_illum.distributed import cluster as cluster_module  # noqa: E402
from lbl_illum.distributed.cluster import DaskCluster  # noqa: E402
from lbl_illum.distributed.rounds import solve_points  # noqa: E402
from lbl_illum.distributed.worker import SceneRecipe  # noqa: E402
from lbl_illum.engine.integrator import Integrator  # noqa: E402
from lbl_illum.errors import InputError  # noqa: E402

from test_rounds_in_process import OFFICE, PLAN, in_process, office_job  # noqa: E402


@pytest.fixture(scope="module")
def local():
    """A scheduler with two single-threaded worker processes on 127.0.0.1, and a checked
    DaskCluster connected to it."""
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address=":0")
    dask = DaskCluster(address=cluster.scheduler_address)
    yield cluster, dask
    dask.close()
    cluster.close()


def on_cluster(dask, scene, options, recipe, points, normals, **kw):
    integ = Integrator(scene, options)
    dask.prepare(recipe, options, integ.fingerprint)
    return solve_points(dask, recipe, integ, points, normals, plan=PLAN, **kw)


def test_two_workers_give_the_bits_of_one_process(local):
    _, dask = local
    scene, P, N, options, recipe = office_job()
    here, _, _ = in_process(scene, options, recipe, P, N)
    there, costs, _ = on_cluster(dask, scene, options, recipe, P, N)
    assert np.array_equal(here.rgb, there.rgb) and here.stats.records == there.stats.records
    assert all(c.seconds["send"] >= 0 and c.seconds["merge"] >= 0 for c in costs.rounds)


class _Killer:
    """A progress display that kills (SIGKILL) a worker busy with a task of round 2 as the
    round's first task comes back."""

    def __init__(self, client, pids):
        self.client, self.pids, self.round, self.killed = client, pids, 0, None

    def describe(self, text):
        if text.startswith("round "):
            self.round = int(text.split()[1])

    def update(self, rays):
        if self.round == 2 and self.killed is None:
            busy = [w for w, tasks in self.client.processing().items() if tasks] or list(self.pids)
            self.killed = self.pids[busy[0]]
            os.kill(self.killed, signal.SIGKILL)


def test_a_worker_killed_mid_run_costs_time_not_results(local):
    cluster, dask = local
    scene, P, N, options, recipe = office_job()
    here, _, _ = in_process(scene, options, recipe, P, N)
    pids = dask.client.run(os.getpid)
    killer = _Killer(dask.client, pids)
    there, _, _ = on_cluster(dask, scene, options, recipe, P, N, progress=killer)
    assert killer.killed is not None
    assert np.array_equal(here.rgb, there.rgb)
    dask.client.wait_for_workers(2, timeout=60)        # the nanny started a new one
    assert killer.killed not in dask.client.run(os.getpid).values()


def test_image_on_two_workers_is_the_image_of_one_process(local):
    from lbl_illum.engine.render import render_image
    from lbl_illum.scene.views import view_from_string
    from lbl_illum.distributed.cluster import InProcess

    _, dask = local
    scene, _, _, options, recipe = office_job()
    view = view_from_string("-vtv -vp 2 0.5 1.5 -vd 0 1 -0.1 -vh 80 -vv 60", scene.unit_scale)
    images = []
    for where in (InProcess(), dask):
        integ = Integrator(scene, options)
        where.prepare(recipe, options, integ.fingerprint, scene, integ.context)

        def shade(points, normals, spacing, taper, where=where, integ=integ):
            return solve_points(where, recipe, integ, points, normals, spacing=spacing, taper=taper,
                                plan=PLAN.__class__(chunk=400, most=2))[0]
        images.append(render_image(scene, view, 24, 18, integrator=integ, shade=shade).rgb)
    assert np.array_equal(images[0], images[1]) and images[0].max() > 0


def test_a_scene_a_worker_cannot_read_is_one_line(local, tmp_path):
    _, dask = local
    scene, _, _, options, _ = office_job()
    missing = SceneRecipe(str(tmp_path / "gone" / "scene.toml"))
    t0 = time.perf_counter()
    with pytest.raises(InputError) as info:
        dask.prepare(missing, options, Integrator(scene, options).fingerprint)
    assert str(info.value).startswith("worker tcp://127.0.0.1:") and "scene.toml" in str(info.value)
    assert "\n" not in str(info.value) and time.perf_counter() - t0 < 10


def test_workers_of_another_version_are_refused(local, monkeypatch):
    cluster, _ = local
    monkeypatch.setattr(cluster_module, "project_identity", lambda: "0.0.0+000000000000")
    with pytest.raises(InputError, match=r"^worker tcp://127\.0\.0\.1:\d+ runs lbl_illum .*, this process "
                                         r"0\.0\.0\+000000000000: install the same version on every worker"):
        DaskCluster(address=cluster.scheduler_address)


def test_a_scheduler_without_workers_is_one_line(monkeypatch):
    monkeypatch.setattr(cluster_module, "WORKER_SECONDS", 1.0)
    empty = LocalCluster(n_workers=0, processes=True, host="127.0.0.1", dashboard_address=":0")
    try:
        with pytest.raises(InputError, match="no workers joined within 1 s"):
            DaskCluster(address=empty.scheduler_address)
    finally:
        empty.close()


@pytest.mark.parametrize("command", ["illuminance", "daylight-factor"])
def test_command_on_the_scheduler_writes_the_bits_of_workers_0(local, tmp_path, capsys, command):
    """The daylight factor's workers replace the scene's sky by the overcast one, as the driver."""
    cluster, _ = local
    base = [command, str(OFFICE / "scene.toml"), "--points", str(OFFICE / "grid.pts"), "--preset", "draft",
            "--bounces", "2", "--samples", "32", "--point-samples", "64", "--chunk-size", "40"]
    assert main(base + ["-o", str(tmp_path / "here.csv"), "--workers", "0"]) == 0
    assert main(base + ["-o", str(tmp_path / "there.csv"), "--scheduler", cluster.scheduler_address,
                        "--cache", str(tmp_path / "c.cache")]) == 0
    err = capsys.readouterr().err
    assert f"on {cluster.scheduler_address} (2 rounds)" in err
    assert (tmp_path / "here.csv").read_bytes() == (tmp_path / "there.csv").read_bytes()
    assert (tmp_path / "c.cache").is_file()


def test_a_year_on_two_workers_is_the_year_of_one_process(local):
    """The daylight coefficients by rounds and the direct sun by chunks, shades closed
    too: the same bits on the cluster as in one process."""
    from lbl_illum.daylight.weather import read_weather
    from lbl_illum.distributed.annual import annual_solver
    from lbl_illum.distributed.cluster import InProcess
    from lbl_illum.engine.annual import annual_light, shaded_scene

    _, dask = local
    scene, P, N, options, recipe = office_job(point_samples=32)
    weather = read_weather(OFFICE.parent / "weather" / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw")
    closed = shaded_scene(scene, ["glazing"], 0.1)
    years = []
    for where in (InProcess(), dask):
        open_ = annual_light(scene, P, N, weather, options, solve=annual_solver(where, recipe.path, PLAN))
        shut = annual_light(closed, P, N, weather, options,
                            solve=annual_solver(where, recipe.path, PLAN, shades=(["glazing"], 0.1)))
        years.append((open_.illuminance, open_.direct_sun, shut.illuminance))
    for a, b in zip(*years):
        assert np.array_equal(a, b)
    assert years[0][2].mean() < years[0][0].mean()
