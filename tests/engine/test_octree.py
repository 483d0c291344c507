"""§3.3 octree: the lookup returns exactly the brute-force set S of Eq. 5 with Eq. 6's test,
whatever the order, batch and thread count of the queries."""

import numba
import numpy as np
from hypothesis import given, settings, strategies as st

from lbl_illum.engine.cache import LevelRecords
from lbl_illum.engine.octree import FRONT_TOLERANCE, MIN_ERROR


def brute_force(qP, qN, P, N, E, R, a, Gr=None, Gt=None, W=None, leak=None, taper=False):
    """Eqs. 5 and 6 evaluated for every (query, record) pair with numpy; with gradients,
    record i contributes max(0, E_i + ∇_r E_i·(N_i × N) + ∇_t E_i·(P − P_i)) per channel.
    With ``W`` the distance is elliptical, sqrt(|d|² + (d·W_i)²), and a record is refused
    in the sectors of its ``leak`` mask (angle of d from the first tangent of N_i).  With
    ``taper`` each weight is 1 − ε_i/a."""
    d = qP[:, None, :] - P[None, :, :]
    dist = np.linalg.norm(d, axis=2)
    if W is not None:
        dist = np.sqrt(dist ** 2 + np.einsum("qrk,rk->qr", d, W.astype(np.float64)) ** 2)
    ndot = np.minimum(qN @ N.T.astype(np.float64), 1.0)
    err = dist / R[None, :] + np.sqrt(1.0 - ndot)
    front = 0.5 * np.einsum("qrk,qrk->qr", d, qN[:, None, :] + N[None, :, :])
    inside = (err < a) & (front >= -FRONT_TOLERANCE * R[None, :])
    if leak is not None:
        from lbl_illum.engine.hemisphere import orthonormal_basis
        from lbl_illum.engine.hessian import LEAK_SECTORS
        t, b = orthonormal_basis(N.astype(np.float64))
        u, v = np.einsum("qrk,rk->qr", d, t), np.einsum("qrk,rk->qr", d, b)
        sector = np.floor(np.arctan2(v, u) * LEAK_SECTORS / (2 * np.pi)).astype(np.int64) % LEAK_SECTORS
        closed = (leak.astype(np.int64)[None, :] >> sector) & 1 == 1
        inside &= ~(closed & (u * u + v * v > 1e-6 * R[None, :].astype(np.float64) ** 2))
    w = np.where(inside, 1.0 - err / a if taper else 1.0 / np.maximum(err, MIN_ERROR), 0.0)
    sw = w.sum(axis=1)
    Eq = np.broadcast_to(E.astype(np.float64)[None], d.shape)
    if Gr is not None:
        cross = np.cross(N.astype(np.float64)[None, :, :], qN[:, None, :])        # N_i × N
        Eq = np.maximum(0.0, Eq + np.einsum("rck,qrk->qrc", Gr.astype(np.float64), cross)
                        + np.einsum("rck,qrk->qrc", Gt.astype(np.float64), d))
    Ei = np.einsum("qr,qrc->qc", w, Eq) / np.where(sw > 0, sw, 1.0)[:, None]
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
    # gradients set after the lookup (as the integrator does) are used by the next one
    Gr = rng.normal(scale=200.0, size=(n_rec, 3, 3)).astype(np.float32)
    Gt = (rng.normal(scale=200.0, size=(n_rec, 3, 3)) / R[:, None, None]).astype(np.float32)
    lv.Gr[:n_rec], lv.Gt[:n_rec] = Gr, Gt
    _, _, Eg = brute_force(qP, qN, P, N, E, R, a, Gr, Gt)
    E_oct, _, _ = lv.lookup(qP, qN, gradients=True)
    assert np.allclose(E_oct, Eg, rtol=1e-4, atol=1e-3)
    # tapered weights (images): the same set S, weights 1 − ε/a
    count_t, sw_t, Et = brute_force(qP, qN, P, N, E, R, a, Gr, Gt, taper=True)
    E_oct, w_oct, n_oct = lv.lookup(qP, qN, gradients=True, taper=True)
    assert np.array_equal(n_oct, count_t)
    assert np.allclose(w_oct, sw_t, rtol=1e-4, atol=1e-6)
    assert np.allclose(E_oct, Et, rtol=1e-4, atol=1e-3)


def test_tapered_weights_leave_no_step_at_the_edge_of_a_domain():
    """Two records on a floor, 100 and 200 lux: a query walking out of the second one's
    domain (ε = a at x = 0.5 m) sees the average jump by more than 10 lux across 0.02 mm
    with the paper's weights; with the tapered ones it changes by less than 0.01 lux (its
    slope there is about 375 lux/m)."""
    a = 0.5
    lv = LevelRecords(a, center=np.zeros(3), half=4.0)
    P = np.array([[0.0, 0.0, 0.0], [-0.2, 0.0, 0.0]])
    N = np.array([[0, 0, 1], [0, 0, 1]], np.float32)
    lv.add(P, N, np.array([1.0, 3.0], np.float32), np.array([[200.0] * 3, [100.0] * 3], np.float32))
    x = np.array([0.49999, 0.50001])
    qP = np.column_stack([x, np.zeros(2), np.zeros(2)])
    qN = np.tile([0.0, 0.0, 1.0], (2, 1))
    paper, _, n = lv.lookup(qP, qN)
    tapered, _, _ = lv.lookup(qP, qN, taper=True)
    assert n.tolist() == [2, 1]
    assert abs(paper[0, 0] - paper[1, 0]) > 10.0
    assert abs(tapered[0, 0] - tapered[1, 0]) < 0.01


def _floor_and_walls(rng, n):
    """Records of a room: a floor and two walls, radii over a decade, values and gradients."""
    P = rng.uniform(0.0, 4.0, (n, 3))
    N = np.zeros((n, 3))
    side = rng.integers(0, 3, n)
    for k in range(3):
        P[side == k, k] = 0.0
        N[side == k, k] = 1.0
    R = (0.1 * 10 ** rng.uniform(0, 1, n)).astype(np.float32)
    E = rng.uniform(0, 1000, (n, 3)).astype(np.float32)
    Gr = rng.normal(scale=100.0, size=(n, 3, 3)).astype(np.float32)
    Gt = rng.normal(scale=100.0, size=(n, 3, 3)).astype(np.float32)
    return P, N.astype(np.float32), R, E, Gr, Gt


def _queries_on(rng, P, N, n):
    """Queries near record positions, on their surfaces, with their normals."""
    pick = rng.integers(0, len(P), n)
    qN = N[pick].astype(np.float64)
    qP = P[pick] + rng.normal(scale=0.05, size=(n, 3)) * (1.0 - qN)
    return qP, qN


def test_large_batches_use_the_sorted_packet_search_and_stay_exact():
    """20,000 records and 6,000 queries (sorted into packets, on every thread) against
    brute force on a sample of the queries."""
    rng = np.random.default_rng(11)
    P, N, R, E, Gr, Gt = _floor_and_walls(rng, 20000)
    lv = LevelRecords(0.2, center=np.full(3, 2.0), half=2.1)
    for s in range(0, len(P), 5000):
        lv.add(P[s:s + 5000], N[s:s + 5000], R[s:s + 5000], E[s:s + 5000], Gr[s:s + 5000], Gt[s:s + 5000])
    qP, qN = _queries_on(rng, P, N, 6000)
    E_oct, w_oct, n_oct = lv.lookup(qP, qN, gradients=True)
    assert n_oct.mean() > 5                                # the queries are covered
    sample = rng.choice(len(qP), 200, replace=False)
    for part in np.array_split(sample, 4):
        count, sw, Ei = brute_force(qP[part], qN[part], P, N, E, R, 0.2, Gr, Gt)
        assert np.array_equal(n_oct[part], count)
        assert np.allclose(w_oct[part], sw, rtol=1e-4)
        assert np.allclose(E_oct[part], Ei, rtol=1e-4, atol=1e-3)


def test_answers_do_not_depend_on_order_batch_or_threads():
    """Bit for bit: the whole batch, the batch shuffled, in calls of 100 queries (unsorted,
    one thread) and one at a time, on one and on all threads."""
    rng = np.random.default_rng(5)
    P, N, R, E, Gr, Gt = _floor_and_walls(rng, 8000)
    lv = LevelRecords(0.3, center=np.full(3, 2.0), half=2.1)
    lv.add(P, N, R, E, Gr, Gt)
    qP, qN = _queries_on(rng, P, N, 5000)
    for gradients in (False, True):
        ref = lv.lookup(qP, qN, gradients=gradients)
        shuffle = rng.permutation(len(qP))
        got = lv.lookup(qP[shuffle], qN[shuffle], gradients=gradients)
        for a, b in zip(ref, got):
            assert np.array_equal(a[shuffle], b)
        parts = [lv.lookup(qP[s:s + 100], qN[s:s + 100], gradients=gradients) for s in range(0, len(qP), 100)]
        for k, a in enumerate(ref):
            assert np.array_equal(a, np.concatenate([p[k] for p in parts]))
        for q in rng.choice(len(qP), 20, replace=False):
            one = lv.lookup(qP[q:q + 1], qN[q:q + 1], gradients=gradients)
            for a, b in zip(ref, one):
                assert np.array_equal(a[q:q + 1], b)
        threads = numba.get_num_threads()
        numba.set_num_threads(1)
        try:
            single = lv.lookup(qP, qN, gradients=gradients)
        finally:
            numba.set_num_threads(threads)
        for a, b in zip(ref, single):
            assert np.array_equal(a, b)


def test_values_written_after_a_lookup_and_records_added_after_it_are_seen():
    rng = np.random.default_rng(2)
    P, N, R, E, Gr, Gt = _floor_and_walls(rng, 3000)
    lv = LevelRecords(0.3, center=np.full(3, 2.0), half=2.1)
    idx = lv.add(P[:2000], N[:2000], R[:2000])            # values not known yet
    qP, qN = _queries_on(rng, P[:2000], N[:2000], 300)
    _, _, n0 = lv.lookup(qP, qN)
    lv.E[idx[:1000]] = E[:1000]                           # a plain write ...
    lv.set_values(idx[1000:], E[1000:2000], Gr[1000:2000], Gt[1000:2000])   # ... and the method
    lv.Gr[idx[:1000]], lv.Gt[idx[:1000]] = Gr[:1000], Gt[:1000]
    for gradients in (False, True):
        got = lv.lookup(qP, qN, gradients=gradients)
        want = brute_force(qP, qN, P[:2000], N[:2000], E[:2000], R[:2000], 0.3,
                           *((Gr[:2000], Gt[:2000]) if gradients else ()))
        assert np.array_equal(got[2], n0) and np.array_equal(got[2], want[0])
        assert np.allclose(got[0], want[2], rtol=1e-4, atol=1e-3)
    lv.add(P[2000:], N[2000:], R[2000:], E[2000:])       # after a lookup: the layout is redone
    got = lv.lookup(qP, qN)
    want = brute_force(qP, qN, P, N, E, R, 0.3)
    assert np.array_equal(got[2], want[0]) and np.allclose(got[0], want[2], rtol=1e-4, atol=1e-6)


def test_memory_per_record_stays_below_200_bytes():
    """Records (128 B), lookup layout (about 48 B) and octree nodes, at exact capacity."""
    rng = np.random.default_rng(3)
    P, N, R, E, Gr, Gt = _floor_and_walls(rng, 50000)
    lv = LevelRecords(0.2, center=np.full(3, 2.0), half=2.1, capacity=len(P))
    lv.add(P, N, R, E, Gr, Gt)
    lv.freeze()
    per_record = sum(lv.nbytes().values()) / len(P)
    assert 170 < per_record < 200


def test_record_sits_in_a_node_of_the_paper_size():
    lv = LevelRecords(0.1, center=np.zeros(3), half=64.0)
    lv.add(np.array([[1.0, 2.0, 3.0]]), np.array([[0, 0, 1.0]]), np.array([2.0]))
    # the node holding record 0 satisfies 2aR < side <= 4aR and contains P
    node = lv.record_node[0]
    side = 2 * lv.node_half[node]
    assert 2 * 0.1 * 2.0 < side <= 4 * 0.1 * 2.0
    assert np.all(np.abs(np.array([1.0, 2.0, 3.0]) - lv.node_center[node]) <= lv.node_half[node])


def test_front_test_excludes_a_record_in_front_of_the_query():
    lv = LevelRecords(0.5, center=np.zeros(3), half=10.0)
    # record on a box top 0.05 above a floor query point: in front of it
    lv.add(np.array([[0.0, 0.0, 0.05]]), np.array([[0, 0, 1.0]]), np.array([1.0]), np.array([[5.0, 5, 5]]))
    _, _, n = lv.lookup(np.array([[0.02, 0.0, 0.0]]), np.array([[0, 0, 1.0]]))
    assert n[0] == 0
    _, _, n = lv.lookup(np.array([[0.02, 0.0, 0.1]]), np.array([[0, 0, 1.0]]))
    assert n[0] == 1


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n_rec=st.integers(1, 200), a=st.sampled_from([0.1, 0.3, 1.0]))
def test_elliptical_domains_and_leak_sectors_equal_brute_force(seed, n_rec, a):
    """Hessian-shaped records: the lookup returns the brute-force set and average."""
    from lbl_illum.engine.hemisphere import orthonormal_basis

    rng = np.random.default_rng(seed)
    P = rng.uniform(-1, 1, (n_rec, 3))
    P[: n_rec // 2, 2] = 0.0
    N = _unit(rng.normal(size=(n_rec, 3)))
    N[: n_rec // 2] = [0, 0, 1]
    R = 10 ** rng.uniform(-1.5, 0, n_rec)
    t, b = orthonormal_basis(N)
    ang = rng.uniform(0, 2 * np.pi, n_rec)
    axis = np.cos(ang)[:, None] * t + np.sin(ang)[:, None] * b
    W = (axis * np.sqrt(rng.uniform(0, 3, n_rec))[:, None]).astype(np.float32)
    W[: n_rec // 4] = 0.0
    leak = rng.integers(0, 2**32, n_rec, dtype=np.uint64).astype(np.uint32)
    leak[rng.random(n_rec) < 0.5] = 0
    N, R = N.astype(np.float32), R.astype(np.float32)
    E = rng.uniform(0, 1000, (n_rec, 3)).astype(np.float32)
    lv = LevelRecords(a, center=np.zeros(3), half=1.01, anisotropic=True)
    lv.add(P, N, R, E, W=W, leak=leak)
    near = P[rng.integers(0, n_rec, 300)] + rng.normal(scale=0.5, size=(300, 3)) * a * R[rng.integers(0, n_rec, 300), None]
    qN = np.tile([0.0, 0.0, 1.0], (300, 1))
    qN[150:] = _unit(rng.normal(size=(150, 3)))
    count, sw, Ei = brute_force(near, qN, P, N, E, R, a, W=W, leak=leak)
    E_oct, w_oct, n_oct = lv.lookup(near, qN)
    assert np.array_equal(n_oct, count)
    assert np.allclose(w_oct, sw, rtol=1e-4) and np.allclose(E_oct, Ei, rtol=1e-4, atol=1e-6)
    # the same records without shapes admit at least as many
    plain = LevelRecords(a, center=np.zeros(3), half=1.01)
    plain.add(P, N, R, E)
    assert np.all(plain.lookup(near, qN)[2] >= n_oct)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n_rec=st.integers(1, 400), a=st.sampled_from([0.05, 0.3, 1.0]),
       shaped=st.booleans())
def test_covers_is_exactly_a_nonzero_lookup_count(seed, n_rec, a, shaped):
    """The placement's coverage test finds a serving record exactly when the lookup does."""
    from lbl_illum.engine.hemisphere import orthonormal_basis

    rng = np.random.default_rng(seed)
    P = rng.uniform(-1, 1, (n_rec, 3))
    P[: n_rec // 2, 2] = 0.0
    N = _unit(rng.normal(size=(n_rec, 3)))
    N[: n_rec // 2] = [0, 0, 1]
    R = (10 ** rng.uniform(-1.5, 0.5, n_rec)).astype(np.float32)
    lv = LevelRecords(a, center=np.zeros(3), half=1.01, anisotropic=shaped)
    shape = {}
    if shaped:
        t, _ = orthonormal_basis(N)
        shape = {"W": (t * rng.uniform(0, 2, (n_rec, 1))).astype(np.float32),
                 "leak": np.where(rng.random(n_rec) < 0.5, 0, rng.integers(0, 2**32, n_rec, dtype=np.uint64))
                 .astype(np.uint32)}
    lv.add(P, N.astype(np.float32), R, **shape)
    qP = np.vstack([P[rng.integers(0, n_rec, 5000)] + rng.normal(scale=0.2, size=(5000, 3)),
                    rng.uniform(-2, 2, (2000, 3))])
    qN = np.tile([0.0, 0.0, 1.0], (len(qP), 1))
    qN[3000:] = _unit(rng.normal(size=(len(qP) - 3000, 3)))
    assert np.array_equal(lv.covers(qP, qN), lv.lookup(qP, qN)[2] > 0)
    assert np.array_equal(lv.covers(qP[:100], qN[:100]), lv.lookup(qP[:100], qN[:100])[2] > 0)   # serial


def test_the_layout_sort_is_stable_on_both_sides_of_the_radix_threshold():
    """Keys with many ties (few distinct values) and keys over all 64 bits: the radix sort
    for many keys and numpy's for few give numpy's stable order."""
    from lbl_illum.engine.octree import RADIX_MIN, _stable_order

    rng = np.random.default_rng(3)
    for n in (RADIX_MIN - 1, RADIX_MIN, 3 * RADIX_MIN):
        for keys in (rng.integers(0, 50, n).astype(np.uint64),
                     rng.integers(0, 2**63, n, dtype=np.uint64) | np.uint64(1 << 63)):
            np.testing.assert_array_equal(_stable_order(keys), np.argsort(keys, kind="stable"))
