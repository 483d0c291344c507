"""§3.3 octree: the lookup returns exactly the brute-force set S of Eq. 5 with Eq. 6's test."""

import numpy as np
from hypothesis import given, settings, strategies as st

from lbl_illum.cache import LevelRecords
from lbl_illum.octree import FRONT_TOLERANCE, MIN_ERROR


def brute_force(qP, qN, P, N, E, R, a):
    """Eqs. 5 and 6 evaluated for every (query, record) pair with numpy."""
    d = qP[:, None, :] - P[None, :, :]
    dist = np.linalg.norm(d, axis=2)
    ndot = np.minimum(qN @ N.T.astype(np.float64), 1.0)
    err = dist / R[None, :] + np.sqrt(1.0 - ndot)
    front = 0.5 * np.einsum("qrk,qrk->qr", d, qN[:, None, :] + N[None, :, :])
    inside = (err < a) & (front >= -FRONT_TOLERANCE * R[None, :])
    w = np.where(inside, 1.0 / np.maximum(err, MIN_ERROR), 0.0)
    sw = w.sum(axis=1)
    Ei = (w @ E.astype(np.float64)) / np.where(sw > 0, sw, 1.0)[:, None]
    return inside.sum(axis=1), sw, Ei


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n_rec=st.integers(1, 300), a=st.sampled_from([0.05, 0.1, 0.3, 1.0, 3.0]),
       spread=st.sampled_from([0.1, 1.0, 30.0]))
def test_octree_lookup_equals_brute_force(seed, n_rec, a, spread):
    rng = np.random.default_rng(seed)
    # records clustered on a few planes (like walls) plus scattered ones, radii over 3 decades
    P = rng.uniform(-spread, spread, (n_rec, 3))
    P[: n_rec // 2, 2] = 0.0
    N = _unit(rng.normal(size=(n_rec, 3)))
    N[: n_rec // 2] = [0, 0, 1]
    N = N.astype(np.float32)
    R = (spread * 10 ** rng.uniform(-3, 0, n_rec)).astype(np.float32)
    E = rng.uniform(0, 1000, (n_rec, 3)).astype(np.float32)
    lv = LevelRecords(a, center=np.zeros(3), half=spread * 1.01)
    # insert in two batches, the second partly outside the root (the tree must grow)
    half = n_rec // 2
    lv.add(P[:half], N[:half], R[:half], E[:half])
    P[half:] *= 1.7
    lv.add(P[half:], N[half:], R[half:], E[half:])
    # queries: near records (so S is often non-empty) and random ones
    near = P[rng.integers(0, n_rec, 200)] + rng.normal(scale=0.3, size=(200, 3)) * R[rng.integers(0, n_rec, 200), None]
    qP = np.vstack([near, rng.uniform(-2 * spread, 2 * spread, (100, 3)), P[:20]])
    qN = _unit(np.vstack([rng.normal(size=(300, 3)), N[:20].astype(np.float64)]))
    qN[:100] = [0, 0, 1]
    count, sw, Ei = brute_force(qP, qN, P, N, E, R, a)
    E_oct, w_oct, n_oct = lv.lookup(qP, qN)
    assert np.array_equal(n_oct, count)
    # the set S is exact; a query within ~1e-5 of a record has a weight set by round-off
    # in sqrt(1 - N·N_i) (float32 normals, different summation order), hence 1e-4
    assert np.allclose(w_oct, sw, rtol=1e-4)
    assert np.allclose(E_oct, Ei, rtol=1e-4, atol=1e-6)


def test_record_sits_in_a_node_of_the_paper_size():
    lv = LevelRecords(0.1, center=np.zeros(3), half=64.0)
    lv.add(np.array([[1.0, 2.0, 3.0]]), np.array([[0, 0, 1.0]]), np.array([2.0]))
    # walk the tree to the node holding record 0 and check 2aR < side <= 4aR
    for node in range(lv.n_nodes):
        if lv.node_first[node] == 0:
            side = 2 * lv.node_half[node]
            assert 2 * 0.1 * 2.0 < side <= 4 * 0.1 * 2.0
            c, h = lv.node_center[node], lv.node_half[node]
            assert np.all(np.abs(np.array([1.0, 2.0, 3.0]) - c) <= h)
            break
    else:
        raise AssertionError("record not found in any node")


def test_front_test_excludes_a_record_in_front_of_the_query():
    lv = LevelRecords(0.5, center=np.zeros(3), half=10.0)
    # record on a box top 0.05 above a floor query point: in front of it
    lv.add(np.array([[0.0, 0.0, 0.05]]), np.array([[0, 0, 1.0]]), np.array([1.0]), np.array([[5.0, 5, 5]]))
    _, _, n = lv.lookup(np.array([[0.02, 0.0, 0.0]]), np.array([[0, 0, 1.0]]))
    assert n[0] == 0
    _, _, n = lv.lookup(np.array([[0.02, 0.0, 0.1]]), np.array([[0, 0, 1.0]]))
    assert n[0] == 1
