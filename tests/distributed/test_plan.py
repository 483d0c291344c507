"""The decomposition of a run into chunks and rounds (lbl_illum.distributed.plan): fixed by
the work, never by the workers."""

import pytest

from lbl_illum.distributed.plan import Decomposition


def test_chunks_cover_the_points_in_order():
    plan = Decomposition(chunk=10, most=4)
    chunks = plan.chunks(35)
    assert [(s.start, s.stop) for s in chunks] == [(0, 10), (10, 20), (20, 30), (30, 35)]
    assert plan.chunks(0) == []


def test_rounds_double_up_to_the_limit():
    plan = Decomposition(chunk=1, most=4)
    assert plan.rounds(12) == [[0], [1, 2], [3, 4, 5, 6], [7, 8, 9, 10], [11]]
    assert Decomposition(most=1).rounds(3) == [[0], [1], [2]]
    assert sum(plan.rounds(1000), []) == list(range(1000))


def test_a_decomposition_needs_positive_sizes():
    with pytest.raises(ValueError):
        Decomposition(chunk=0)
