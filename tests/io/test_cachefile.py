"""Cache files: reuse gives identical results without new primary evaluations; wrong caches are
refused; the format (docs/cache-files.md), merging, two processes sharing one file.  The
``lbl-illum cache`` commands: tests/cli/test_cache.py."""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from lbl_illum import InputError, IrradianceCache, Options
from lbl_illum.io.cachefile import CACHE_FORMAT_VERSION, CacheData, merge_cache_data, read_cache_file, record_settings, write_cache_file
from lbl_illum.engine.integrator import Integrator
from lbl_illum.io.cachefile import attach_cache_file

from conftest import CACHE_OPTIONS, EXAMPLES, ROOT


OPTS = Options(**CACHE_OPTIONS)


@pytest.mark.parametrize("opts", [OPTS, OPTS.replace(interpolation="hessian")], ids=["round", "elliptical"])
def test_second_run_from_file_is_identical_and_computes_no_record(office_quarter, tmp_path, opts):
    scene, points, normals = office_quarter
    first = Integrator(scene, opts)
    r1 = first.compute(points, normals)
    assert r1.stats.primary_evaluations > 0
    path = tmp_path / "office.lblcache"
    first.cache.save(path)
    second = Integrator(scene, opts)
    second.cache = IrradianceCache.load(path, second.fingerprint)
    assert second.cache.record_counts == first.cache.record_counts
    r2 = second.compute(points, normals)
    assert r2.stats.primary_evaluations == 0
    assert np.array_equal(r1.illuminance, r2.illuminance)
    assert r2.stats.rays < r1.stats.rays / 5
    if opts.interpolation == "hessian":      # the domains' shapes and leak sectors came back
        for a, b in zip(first.cache.levels, second.cache.levels):
            n = a.count
            assert b.anisotropic and np.array_equal(a.W[:n], b.W[:n]) and np.array_equal(a.leak[:n], b.leak[:n])
        assert any(lv.leak[:lv.count].any() for lv in second.cache.levels)


def test_cache_of_other_settings_or_scene_is_refused(office_quarter, tmp_path):
    scene, points, normals = office_quarter
    integ = Integrator(scene, OPTS)
    integ.compute(points[:2], normals[:2])
    path = tmp_path / "c.lblcache"
    integ.cache.save(path)
    other = Integrator(scene, OPTS.replace(bounces=3))
    with pytest.raises(InputError, match="another scene or other settings"):
        IrradianceCache.load(path, other.fingerprint)


def test_damaged_cache_is_refused(office_quarter, tmp_path):
    scene, points, normals = office_quarter
    integ = Integrator(scene, OPTS)
    integ.compute(points[:2], normals[:2])
    path = tmp_path / "c.lblcache"
    integ.cache.save(path)
    data = bytearray(path.read_bytes())
    path.write_bytes(bytes(data[: len(data) // 2]))
    with pytest.raises(InputError, match="c.lblcache"):
        IrradianceCache.load(path, integ.fingerprint)


# -- the file format (docs/cache-files.md) ---------------------------------------------------

def _rezip(path, header=None, arrays=None):
    """Rewrite a cache file's members (a file a run did not write)."""
    with np.load(path) as npz:
        members = {k: npz[k] for k in npz.files}
    if header is not None:
        members["header"] = np.array(json.dumps(header))
    members.update(arrays or {})
    with open(path, "wb") as fh:              # (np.savez would add .npz to a file name)
        np.savez(fh, **members)


def test_header_holds_version_fingerprint_settings_counts_and_checksum(office_cache):
    path, integ = office_cache
    with np.load(path) as npz:
        header = json.loads(str(npz["header"]))
    assert header["version"] == CACHE_FORMAT_VERSION == 2
    assert header["fingerprint"] == integ.fingerprint
    assert [lv["records"] for lv in header["levels"]] == integ.cache.record_counts
    assert [lv["accuracy"] for lv in header["levels"]] == integ.accuracies
    assert len(header["checksum"]) == 64
    s = header["settings"]
    assert s == record_settings(integ.scene, OPTS)
    assert (s["accuracy"], s["bounces"], s["samples"]) == (0.2, 2, 128)
    assert s["sky"]["type"] == "cie-overcast" and s["sky"]["horizontal_illuminance"] == 10000
    assert set(s["materials"]) == {"wall", "floor", "ceiling", "ground", "glazing"}
    assert s["geometry"]["triangles"] == len(integ.scene.triangles)


def test_saving_twice_gives_the_same_bytes(office_cache, tmp_path):
    path, integ = office_cache
    again = tmp_path / "again.lblcache"
    IrradianceCache.load(path).save(again)
    assert again.read_bytes() == path.read_bytes()


@pytest.mark.parametrize("damage", ["truncate", "flip", "header", "count", "array", "text", "empty"])
def test_damaged_or_edited_file_is_refused_in_one_line(office_cache, tmp_path, damage):
    path, integ = office_cache
    bad = tmp_path / "bad.lblcache"
    bad.write_bytes(path.read_bytes())
    data = bytearray(path.read_bytes())
    if damage == "truncate":
        bad.write_bytes(bytes(data[: len(data) - 1000]))
    elif damage == "flip":                    # inside the record arrays: the zip's CRC or the checksum
        data[len(data) // 2] ^= 0x40
        bad.write_bytes(bytes(data))
    elif damage == "header":                  # an edited header no longer matches its checksum
        header = read_cache_file(path).header
        header["settings"]["samples"] = 64
        _rezip(bad, header=header)
    elif damage == "count":
        header = read_cache_file(path).header
        header["levels"][1]["records"] -= 1
        _rezip(bad, header=header)
    elif damage == "array":
        with np.load(path) as npz:
            E = npz["L1_E"].copy()
        E[0, 0] += 1.0
        _rezip(bad, arrays={"L1_E": E})
    elif damage == "text":
        bad.write_text("not a cache\n")
    else:
        bad.write_bytes(b"")
    with pytest.raises(InputError) as info:
        IrradianceCache.load(bad, integ.fingerprint)
    message = str(info.value)
    assert "\n" not in message and message.startswith("bad.lblcache: ")
    assert any(word in message for word in ("damaged", "truncated", "not an lbl_illum cache"))


def _edited(values, name, row, change):
    """A copy of ``values`` with one record's entry of array ``name`` changed."""
    arr = values[name].copy()
    change(arr, row)
    return {**values, name: arr}


def _scale_normal(s):
    def change(arr, row):
        arr[row] *= s
    return change


def _set(index, value):
    def change(arr, row):
        arr[(row, *index)] = value
    return change


#: (case, array of level 1, change of one record, message): physically impossible records
#: that a correct checksum does not make acceptable.
IMPOSSIBLE_RECORDS = [
    ("normal too short", "N", _scale_normal(0.99), r"L1_N: record 3 has a normal of length 0\.99, not a unit vector"),
    ("normal too long", "N", _scale_normal(1.002), r"L1_N: record 3 has a normal of length 1\.002"),
    ("normal zero", "N", _scale_normal(0.0), r"L1_N: record 3 has a normal of length 0,"),
    ("normal NaN", "N", _set((1,), np.nan), r"array L1_N holds non-finite numbers"),
    ("irradiance negative", "E", _set((2,), -1e-3), r"L1_E: record 3 has a negative irradiance -0\.001 lux"),
    ("irradiance infinite", "E", _set((0,), np.inf), r"array L1_E holds non-finite numbers"),
    ("irradiance NaN", "E", _set((0,), np.nan), r"array L1_E holds non-finite numbers"),
    ("radius zero", "R", _set((), 0.0), r"array L1_R holds radii <= 0"),
    ("radius negative", "R", _set((), -0.5), r"array L1_R holds radii <= 0"),
    ("radius infinite", "R", _set((), np.inf), r"array L1_R holds non-finite numbers"),
    ("position NaN", "P", _set((2,), np.nan), r"array L1_P holds non-finite numbers"),
    ("position infinite", "P", _set((0,), -np.inf), r"array L1_P holds non-finite numbers"),
    ("rotational gradient NaN", "Gr", _set((1, 2), np.nan), r"array L1_Gr holds non-finite numbers"),
    ("translational gradient infinite", "Gt", _set((0, 0), np.inf), r"array L1_Gt holds non-finite numbers"),
]


@pytest.mark.parametrize("case, name, change, message", IMPOSSIBLE_RECORDS, ids=[c[0] for c in IMPOSSIBLE_RECORDS])
def test_records_no_evaluation_gives_are_refused_despite_a_correct_checksum(office_cache, tmp_path, case, name, change,
                                                                            message):
    """One record of level 1 edited and the file re-written by the module's own writer (so
    the checksum is right): the loader refuses it, naming the file, the array and the record."""
    path, integ = office_cache
    data = read_cache_file(path)
    assert data.header["levels"][1]["records"] > 3
    arrays = _edited(data.arrays, f"L1_{name}", 3, change)
    bad = tmp_path / "edited.lblcache"
    write_cache_file(bad, CacheData(data.header, arrays))
    with pytest.raises(InputError, match=r"^edited.lblcache: damaged cache file \(.*" + message) as info:
        IrradianceCache.load(bad, integ.fingerprint)
    assert "\n" not in str(info.value)
    # the same file with the record as written loads: only the edit is refused
    write_cache_file(bad, CacheData(data.header, data.arrays))
    assert IrradianceCache.load(bad, integ.fingerprint).record_counts == integ.cache.record_counts


def test_written_records_have_unit_normals_and_non_negative_irradiance(office_cache):
    """What the checks demand holds, with room to spare, for what a run writes."""
    path, _ = office_cache
    data = read_cache_file(path)
    for k in range(len(data.header["levels"])):
        level = data.level(k)
        if len(level["P"]):
            length = np.linalg.norm(level["N"].astype(np.float64), axis=1)
            assert np.all(np.abs(length - 1) < 1e-6) and np.all(level["E"] >= 0)


def test_file_of_another_version_is_refused(office_cache, tmp_path):
    path, integ = office_cache
    bad = tmp_path / "future.lblcache"
    bad.write_bytes(path.read_bytes())
    header = read_cache_file(path).header
    header["version"] = 3
    _rezip(bad, header=header)
    with pytest.raises(InputError, match=r"future.lblcache: cache format version 3; this program reads versions 1, 2"):
        IrradianceCache.load(bad, integ.fingerprint)


def test_version_1_files_are_still_read(office_quarter, office_cache, tmp_path):
    """A version-1 file (one root cube, checksum of the arrays only) loads and answers as
    the version-2 file of the same records does."""
    path, integ = office_cache
    data = read_cache_file(path)
    from lbl_illum.io.cachefile import _checksum_v1
    h = data.header
    old = {"format": h["format"], "version": 1, "fingerprint": h["fingerprint"], "domains": h["domains"],
           "accuracy": [lv["accuracy"] for lv in h["levels"]], "records": data.record_counts,
           "center": h["center"], "half": h["half"], "checksum": _checksum_v1(data.arrays)}
    v1 = tmp_path / "v1.lblcache"
    with open(v1, "wb") as fh:
        np.savez(fh, header=np.array(json.dumps(old)), **data.arrays)
    scene, points, normals = office_quarter
    results = []
    for p in (path, v1):
        again = Integrator(scene, OPTS)
        again.cache = IrradianceCache.load(p, again.fingerprint)
        results.append(again.compute(points, normals))
    assert results[1].stats.primary_evaluations == 0
    assert np.array_equal(results[0].rgb, results[1].rgb)


def test_other_settings_are_named_in_the_refusal_and_rebuild_replaces_the_file(office_quarter, office_cache, tmp_path):
    path, integ = office_cache
    scene, points, normals = office_quarter
    target = tmp_path / "c.lblcache"
    target.write_bytes(path.read_bytes())
    other = Integrator(scene, OPTS.replace(samples=64))
    with pytest.raises(InputError, match=r"c.lblcache: cache was made for another scene or other settings "
                                         r"\(samples differ\); use another file or rebuild it"):
        attach_cache_file(other, target)
    attach_cache_file(other, target, rebuild=True)
    assert other.cache is None
    other.compute(points[:3], normals[:3])
    assert read_cache_file(target).fingerprint == other.fingerprint
    assert IrradianceCache.load(target, other.fingerprint).record_counts == other.cache.record_counts


def test_missing_and_non_cache_files(tmp_path):
    with pytest.raises(InputError, match="nothere.lblcache: no such cache file"):
        IrradianceCache.load(tmp_path / "nothere.lblcache")
    with pytest.raises(InputError, match="is a folder"):
        IrradianceCache.load(tmp_path)
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(InputError, match="other.npz: not an lbl_illum cache file"):
        IrradianceCache.load(tmp_path / "other.npz")


def test_accuracy_zero_levels_are_not_written(office_quarter, tmp_path):
    """Records of a level with accuracy 0 (here: point samples) answer only their own query:
    the file leaves them out, and a rerun from it repeats the first run exactly."""
    scene, points, normals = office_quarter
    opts = OPTS.replace(point_samples=256)
    path = tmp_path / "p.lblcache"
    first = Integrator(scene, opts)
    attach_cache_file(first, path)
    r1 = first.compute(points, normals)
    assert first.cache.levels[0].accuracy == 0 and r1.stats.records[0] == len(points)
    assert read_cache_file(path).record_counts[0] == 0
    second = Integrator(scene, opts)
    attach_cache_file(second, path)
    r2 = second.compute(points, normals)
    assert r2.stats.new_records[1:] == [0, 0]
    assert np.array_equal(r1.rgb, r2.rgb)


# -- merging -----------------------------------------------------------------------------------

def _record_set(data: CacheData, k: int) -> set:
    a = data.level(k)
    return {(p.tobytes(), n.tobytes()) for p, n in zip(a["P"], a["N"])}


def test_save_merges_records_written_by_others(office_quarter, tmp_path):
    scene, points, normals = office_quarter
    path = tmp_path / "shared.lblcache"
    a, b = Integrator(scene, OPTS), Integrator(scene, OPTS)
    a.compute(points[0::2], normals[0::2])
    b.compute(points[1::2], normals[1::2])
    a.cache.save(path)
    b.cache.save(path)                    # b did not read the file: the save adds a's records
    both = read_cache_file(path)
    for k in range(3):
        mine, theirs = _record_set(a.cache.to_data(), k), _record_set(b.cache.to_data(), k)
        assert _record_set(both, k) == mine | theirs
        assert both.record_counts[k] == len(mine | theirs)
    b.cache.save(path)                    # no duplicates: the same records are not added twice
    assert read_cache_file(path).record_counts == both.record_counts
    b.cache.save(path, merge=False)       # without merging, the file holds b's records only
    assert read_cache_file(path).record_counts == b.cache.record_counts
    merged = IrradianceCache.load(path)   # loads: root cubes hold every record
    assert merged.record_counts == b.cache.record_counts


def test_merge_refuses_incompatible_caches(office_quarter, office_cache):
    path, integ = office_cache
    scene, points, normals = office_quarter
    other = Integrator(scene, OPTS.replace(bounces=3))
    other.compute(points[:2], normals[:2])
    with pytest.raises(InputError, match=r"bounces, level_accuracy|bounces differ"):
        merge_cache_data(read_cache_file(path), other.cache.to_data())


CONCURRENT = textwrap.dedent('''
    import os, sys, time
    from lbl_illum import Options, load_scene, read_points
    from lbl_illum.engine.integrator import Integrator
    from lbl_illum.io.cachefile import attach_cache_file

    scene_file, points_file, shared, own, me, other, part = sys.argv[1:8]
    scene = load_scene(scene_file)
    points, normals = read_points(points_file, scene.unit_scale)
    part = int(part)
    points, normals = points[part::2], normals[part::2]

    class Barrier:
        # before the shared file is written: keep a private copy of this run's records,
        # then wait for the other process, so that both write at the same moment
        def __init__(self):
            self.integ = None
        def describe(self, text):
            if text == "writing the cache file":
                self.integ.cache.save(own, merge=False)
                open(me, "w").close()
                t = time.monotonic()
                while not os.path.exists(other) and time.monotonic() - t < 60:
                    time.sleep(0.005)
        def update(self, rays):
            pass

    bar = Barrier()
    integ = Integrator(scene, Options(accuracy=0.2, bounces=2, samples=128), progress=bar)
    bar.integ = integ
    attach_cache_file(integ, shared)
    integ.compute(points, normals)
''')


def test_two_processes_with_one_cache_file_keep_the_records_of_both(tmp_path):
    script = tmp_path / "run.py"
    script.write_text(CONCURRENT)
    shared = tmp_path / "shared.lblcache"
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    args = [str(EXAMPLES / "office" / "scene.toml"), str(EXAMPLES / "office" / "grid.pts"), str(shared)]
    procs = [subprocess.Popen([sys.executable, str(script), *args, str(tmp_path / f"own{i}.lblcache"),
                               str(tmp_path / f"ready{i}"), str(tmp_path / f"ready{1 - i}"), str(i)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
             for i in (0, 1)]
    for p in procs:
        out, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
    both = read_cache_file(shared)            # complete and uncorrupted
    own = [read_cache_file(tmp_path / f"own{i}.lblcache") for i in (0, 1)]
    for k in range(3):
        union = _record_set(own[0], k) | _record_set(own[1], k)
        assert _record_set(both, k) == union
        assert both.record_counts[k] == len(union)
    assert not (tmp_path / "shared.lblcache.lock").exists()
    assert sorted(x.name for x in tmp_path.iterdir() if x.name.startswith(".")) == []    # no temporary files left


def test_lock_excludes_a_second_process(tmp_path):
    from lbl_illum.io.locking import file_lock

    path = tmp_path / "x.lblcache"
    probe = ("import sys\nfrom lbl_illum.io.locking import file_lock, LockTimeout\n"
             "try:\n    with file_lock(sys.argv[1], timeout=0.3):\n        print('GOT')\n"
             "except LockTimeout:\n    print('BUSY')\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    with file_lock(path):
        busy = subprocess.run([sys.executable, "-c", probe, str(path)], capture_output=True, text=True, env=env)
    free = subprocess.run([sys.executable, "-c", probe, str(path)], capture_output=True, text=True, env=env)
    assert busy.stdout.strip() == "BUSY" and free.stdout.strip() == "GOT"
