"""Record sets and their merging (lbl_illum.distributed.records, io.cachefile.merge_cache_parts)."""

import numpy as np

from lbl_illum.distributed.records import merge_round, record_delta, record_set
from lbl_illum.engine.cache import IrradianceCache
from lbl_illum.io.cachefile import cache_from_data, merge_cache_data


def cache_with(P, seed=0):
    cache = IrradianceCache("fp", [0.2, 0.1], np.zeros(3), 1.0)
    rng = np.random.default_rng(seed)
    N = np.tile([0.0, 0.0, 1.0], (len(P), 1))
    cache.levels[1].add(P, N, rng.uniform(0.05, 0.2, len(P)), E=rng.uniform(0, 50, (len(P), 3)))
    return cache


def test_merging_parts_at_once_is_merging_them_one_by_one():
    rng = np.random.default_rng(3)
    base = record_set(cache_with(rng.uniform(-1, 1, (50, 3))))
    shared = rng.uniform(-1, 1, (5, 3))                      # made by two parts: kept once
    parts = [record_set(cache_with(np.vstack([rng.uniform(-3, 3, (20, 3)), shared]), seed=i)) for i in range(4)]
    one_by_one = base
    for part in parts:
        one_by_one, _ = merge_cache_data(one_by_one, part)
    at_once = merge_round(base, parts)
    assert at_once.record_counts == one_by_one.record_counts == [0, 50 + 4 * 20 + 5]
    assert at_once.header["levels"] == one_by_one.header["levels"]
    for name, arr in one_by_one.arrays.items():
        assert np.array_equal(at_once.arrays[name], arr), name


def test_a_delta_holds_only_the_new_records_and_merges_back_to_the_cache():
    rng = np.random.default_rng(4)
    base = record_set(cache_with(rng.uniform(-1, 1, (30, 3))))
    cache = cache_from_data(base)
    cache.levels[1].add(rng.uniform(-2, 2, (7, 3)), np.tile([0.0, 0.0, 1.0], (7, 1)), np.full(7, 0.1))
    delta = record_delta(cache, base)
    assert delta.record_counts == [0, 7]
    merged = merge_round(base, [delta])
    assert np.array_equal(merged.arrays["L1_P"], cache.levels[1].P[:37])
    assert merged.header["levels"][1]["half"] >= cache.levels[1].node_half[0]
