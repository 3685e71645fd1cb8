"""ligwf.analysis.granules.bonds: reference (networkx BFS, numpy bond criterion) vs compiled fast path
(ligwf.analysis.granules_numba) on real dumps, random frames and random graphs; bond criterion
against a per-contact scalar evaluation; volumes and periodic CoM."""

from __future__ import annotations

import math
from pathlib import Path

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from ligwf import liquids
from ligwf.liquids import washino
from ligwf.liquids.capillary import rupture_distance
from ligwf.analysis.frames.dumps import ContactFrame, ParticleFrame
from ligwf.errors import DumpReadError
from ligwf.analysis.granules.bonds import (BondCriterion, bonded_contacts, bonded_contacts_reference,
                                          comoving, granule_table, identify_fast,
                                          identify_reference, label_fast, label_reference)
from ligwf.analysis.granules.bridge_law import Liquid, force_law_positive
from ligwf.analysis.granules.communities import louvain_labels
from wetdump import wet_case_frames


@pytest.fixture(scope="module")
def real(engine, tmp_path_factory):
    case, _, frames = wet_case_frames(engine, tmp_path_factory)
    return case.scaled, frames


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("angle", [30.0, 5.0, 180.0])
def test_reference_equals_fast_on_real_dumps(real, angle):
    scaled, frames = real
    liquid = Liquid.from_scaled(scaled)
    counts, L = [], scaled.drum.length
    for p, c in frames:
        crit = BondCriterion(0.0, angle)
        ref = identify_reference(p, c, liquid, crit, 1, L)
        fast = identify_fast(p, c, liquid, crit, 1, L)
        _same_identification(p, ref, fast)
        t_ref = granule_table(p, ref.labels, scaled.cg, ref.unwrapped_axis, 1, 0.0, L,
                              ref.percolating)
        t_fast = granule_table(p, fast.labels, scaled.cg, fast.unwrapped_axis, 1, 0.0, L,
                               fast.percolating)
        np.testing.assert_array_equal(t_ref["members"], t_fast["members"])
        np.testing.assert_array_equal(t_ref["volume"], t_fast["volume"])
        np.testing.assert_array_equal(t_ref["percolating"], t_fast["percolating"])
        np.testing.assert_allclose(t_ref[["com_x", "com_y", "com_z"]],
                                   t_fast[["com_x", "com_y", "com_z"]], atol=1e-15)
        # volumes sum to the total particle volume, singletons included
        assert t_fast["volume"].sum() == pytest.approx(p.volumes.sum(), rel=1e-12)
        assert t_fast["members"].sum() == len(p)
        np.testing.assert_allclose(t_fast["primary_volume"], t_fast["volume"] / 27.0)
        counts.append(len(t_fast))
    if angle == 5.0:
        assert max(counts) > 5, "a strict angle splits the bed into several granules"


def _same_identification(p, ref, fast, atol=1e-15):
    """The fused compiled pass == the reference: same bonds in the same order, same
    canonical labels, same percolating granules, the same unwrapped positions (to rounding:
    the reference sums displacements along its BFS tree, the fused pass adds whole periods)."""
    np.testing.assert_array_equal(fast.i, ref.i)
    np.testing.assert_array_equal(fast.j, ref.j)
    np.testing.assert_array_equal(fast.labels, ref.labels)
    np.testing.assert_array_equal(fast.percolating, ref.percolating)
    assert fast.axis == ref.axis
    if ref.unwrapped_axis is None:
        assert fast.unwrapped_axis is None
    else:
        np.testing.assert_allclose(fast.unwrapped_axis, ref.unwrapped_axis, rtol=0, atol=atol)


def _same_bonds(p, c, liquid, crit):
    """Compiled bond test == numpy reference: the same pairs in the same order, the same
    forces (to rounding of the transcendental functions), and so the same granules."""
    i, j, f = bonded_contacts(p, c, liquid, crit)
    ri, rj, rf = bonded_contacts_reference(p, c, liquid, crit)
    np.testing.assert_array_equal(i, ri)
    np.testing.assert_array_equal(j, rj)
    np.testing.assert_allclose(f, rf, rtol=1e-13, atol=0)
    np.testing.assert_array_equal(label_fast(len(p), i, j), label_reference(len(p), ri, rj))
    return i, j


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("model", ["washino", "easo", "none"])
@pytest.mark.parametrize("crit", [BondCriterion(), BondCriterion(1e-4, 30.0),
                                  BondCriterion(0.0, 5.0), BondCriterion(0.0, 180.0)])
def test_compiled_bonds_equal_numpy_on_real_dumps(real, model, crit):
    scaled, frames = real
    base = Liquid.from_scaled(scaled)
    liquid = Liquid(model, base.surface_tension, base.contact_angle_rad, base.liquid_content)
    bonded = 0
    for p, c in frames:
        i, _ = _same_bonds(p, c, liquid, crit)
        bonded += len(i)
    assert (bonded > 0) == (model != "none")


@st.composite
def wet_frames(draw):
    """Random particles (radii, liquid, velocities, some at rest, ids with gaps or not) and
    contacts whose gaps span touching, bridged and beyond-rupture pairs."""
    n = draw(st.integers(2, 40))
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    ids = np.arange(1, n + 1) if draw(st.booleans()) else np.sort(rng.choice(10 * n, n, replace=False)) + 1
    radii = rng.uniform(2e-4, 1.5e-3, n)
    vel = rng.normal(0, 1, (n, 3)) * (rng.uniform(size=(n, 1)) > 0.1)   # ~10 % at rest
    vel[: n // 3] = vel[0] + rng.normal(0, 0.05, (n // 3, 3))            # a co-moving group
    content = rng.uniform(0.0, 0.05, n) if draw(st.booleans()) else None
    m = draw(st.integers(0, 3 * n))
    a = rng.integers(0, n, m)
    b = (a + rng.integers(1, n, m)) % n
    delta = -rng.uniform(-0.05, 0.4, m) * (radii[a] + radii[b])          # overlap, m
    p = ParticleFrame(Path("synthetic"), 0, 0.0, ids.astype(np.int64), np.ones(n, np.int32),
                      rng.uniform(0, 0.01, (n, 3)), vel, radii, content)
    c = ContactFrame(Path("synthetic"), 0, ids[np.minimum(a, b)], ids[np.maximum(a, b)], delta)
    model = draw(st.sampled_from(["washino", "easo"]))
    liquid = Liquid(model, draw(st.floats(0.0, 0.08)), math.radians(draw(st.floats(0.0, 89.0))),
                    0.02)
    crit = BondCriterion(draw(st.sampled_from([0.0, 1e-6, 1e-4])), draw(st.floats(0.0, 180.0)))
    return p, c, liquid, crit


@settings(max_examples=300, deadline=None)
@given(wet_frames())
def test_compiled_bonds_equal_numpy_on_random_frames(frame):
    p, c, liquid, crit = frame
    _same_bonds(p, c, liquid, crit)
    for need_force in (False, True):
        fast = identify_fast(p, c, liquid, crit, 1, 0.01, need_force)
        _same_identification(p, identify_reference(p, c, liquid, crit, 1, 0.01), fast)
        assert (fast.force is not None) or not need_force


@settings(max_examples=200, deadline=None)
@given(wet_frames(), st.floats(1e-4, 0.05))
def test_force_law_shortcut_keeps_the_bonds(frame, content):
    """Where the washino law is provably positive, the fused pass skips it: same bonds."""
    p, c, liquid, crit = frame
    r = float(p.radii[0])
    p = ParticleFrame(p.path, 0, 0.0, p.ids, p.types, p.positions, p.velocities,
                      np.full(len(p), r), np.full(len(p), content))
    liquid = Liquid("washino", max(liquid.surface_tension, 1e-3), liquid.contact_angle_rad, 0.02)
    crit = BondCriterion(0.0, crit.max_velocity_angle_deg)
    assert force_law_positive(p, liquid, p.liquid_content)
    fast = identify_fast(p, c, liquid, crit, 1, 0.01)
    assert fast.force is None
    _same_identification(p, identify_reference(p, c, liquid, crit, 1, 0.01), fast)


def test_bonded_contacts_unknown_id_names_it():
    p = _frame([5e-4] * 3, np.zeros((3, 3)), np.ones((3, 3)))
    c = ContactFrame(Path("synthetic"), 0, np.array([1, 2]), np.array([2, 7]), np.array([0.0, 0.0]))
    with pytest.raises(DumpReadError, match="no particle with id 7"):
        bonded_contacts(p, c, Liquid("washino", 0.02, 0.3, 0.02))


@pytest.mark.engine
@pytest.mark.mpi
def test_bond_criterion_matches_scalar_evaluation(real):
    """Vectorised bond decision == a per-contact loop over the scalar force law."""
    scaled, frames = real
    liquid = Liquid.from_scaled(scaled)
    p, c = frames[0]
    crit = BondCriterion(min_bridge_force=1e-4, max_velocity_angle_deg=30.0)
    i, j, force = bonded_contacts(p, c, liquid, crit)
    got = set(zip(p.ids[i].tolist(), p.ids[j].tolist()))
    expected, near = set(), 0
    for a, b, delta in zip(c.id1.tolist(), c.id2.tolist(), c.delta.tolist()):
        ia, ib = int(np.searchsorted(p.ids, a)), int(np.searchsorted(p.ids, b))
        f = liquids.get("washino").capillary_force(p.radii[ia], p.radii[ib], -delta,
                                                   scaled.liquid_values.surface_tension,
                                                   math.radians(scaled.liquid_values.contact_angle_deg),
                                                   p.liquid_content[ia], p.liquid_content[ib])
        va, vb = p.velocities[ia], p.velocities[ib]
        cosang = float(va @ vb) / (float(np.linalg.norm(va)) * float(np.linalg.norm(vb)))
        angle = math.degrees(math.acos(max(-1.0, min(1.0, cosang))))
        if abs(f - 1e-4) < 1e-12 or abs(angle - 30.0) < 1e-9:
            near += 1
            continue
        if f > 1e-4 and angle < 30.0:
            expected.add((a, b))
    assert near == 0
    assert got == expected and 0 < len(got) < len(c)
    # separated pairs (non-touching bridges) are among the bonds
    bonded_delta = c.delta[np.isin(c.id1 * 10**6 + c.id2, p.ids[i] * 10**6 + p.ids[j])]
    assert (bonded_delta < 0).any()


def test_comoving_rules():
    v = np.array([[1.0, 0, 0], [1.0, 0, 0], [0, 0, 0], [1.0, 0, 0]])
    w = np.array([[1.0, 0.5, 0], [-1.0, 0, 0], [3.0, 1, 0], [1.0, 1.0, 0]])
    np.testing.assert_array_equal(comoving(v, w, 30.0), [True, False, True, False])
    np.testing.assert_array_equal(comoving(v, w, 46.0), [True, False, True, True])


def _frame(radii, positions, velocities, content=0.02) -> ParticleFrame:
    n = len(radii)
    return ParticleFrame(Path("synthetic"), 0, 0.0, np.arange(1, n + 1), np.ones(n, np.int32),
                         np.asarray(positions, float), np.asarray(velocities, float),
                         np.asarray(radii, float), np.full(n, content))


def test_broken_bridge_and_threshold():
    """Beyond the rupture distance there is no bond; a threshold drops weak bridges."""
    from ligwf.analysis.frames.dumps import ContactFrame

    r = 0.0005
    p = _frame([r] * 4, np.zeros((4, 3)), np.tile([0.1, 0, 0], (4, 1)))
    liquid = Liquid("washino", 0.024, math.radians(30), 0.02)
    vol = washino.bridge_volume(r, r, 0.02, 0.02)
    rupture = rupture_distance(vol, math.radians(30))
    c = ContactFrame(Path("synthetic"), 0, np.array([1, 2, 3]), np.array([2, 3, 4]),
                     np.array([1e-6, -0.5 * rupture, -1.01 * rupture]))
    i, j, f = bonded_contacts(p, c, liquid)
    assert list(zip(i, j)) == [(0, 1), (1, 2)]
    strong = float(f[0])
    i, j, _ = bonded_contacts(p, c, liquid, BondCriterion(min_bridge_force=0.99 * strong))
    assert list(zip(i, j)) == [(0, 1)]


def _all_bonded(pos, i, j, length):
    """Identify with every contact (i, j) a bond (overlapping, co-moving partners), both ways."""
    n = len(pos)
    p = _frame([5e-4] * n, pos, np.zeros((n, 3)))
    c = ContactFrame(Path("synthetic"), 0, np.asarray(i, np.int64) + 1, np.asarray(j, np.int64) + 1,
                     np.full(len(i), 1e-6))
    liquid = Liquid("washino", 0.02, math.radians(30), 0.02)
    ref = identify_reference(p, c, liquid, BondCriterion(), 1, length)
    fast = identify_fast(p, c, liquid, BondCriterion(), 1, length)
    assert len(fast.i) == len(i)
    return p, ref, fast


def test_periodic_centre_of_mass():
    """A granule straddling y = 0 / y = L has its centre at the boundary, not mid-box."""
    L = 0.009
    pos = [[0, 0.0004, 0], [0, L - 0.0004, 0], [0.01, 0.0045, 0]]
    p, ref, fast = _all_bonded(pos, [0], [1], L)
    t = granule_table(p, fast.labels, 1.0, fast.unwrapped_axis, 1, 0.0, L, fast.percolating)
    assert t["members"].tolist() == [2, 1]
    assert not t["percolating"].any()
    com_y = t.loc[0, "com_y"]
    assert min(com_y, L - com_y) < 1e-12          # at the boundary (0 or L)
    naive = granule_table(p, fast.labels, 1.0, None, 1, 0.0, L)
    assert naive.loc[0, "com_y"] == pytest.approx(L / 2)   # what not unwrapping gives


def test_percolating_ring_is_flagged_and_kept_in_the_box():
    """A chain closing on itself around the periodic axis percolates (both implementations);
    having no unwrapped layout, its members keep their in-box positions."""
    L = 1.0
    y = np.array([0.05, 0.2, 0.45, 0.7, 0.5])          # ring 0-1-2-3-0 and a singleton
    pos = np.column_stack([np.zeros(5), y, np.zeros(5)])
    p, ref, fast = _all_bonded(pos, [0, 1, 2, 0], [1, 2, 3, 3], L)
    assert fast.percolating.tolist() == ref.percolating.tolist() == [True, False]
    np.testing.assert_array_equal(fast.unwrapped(p.positions), pos)
    np.testing.assert_array_equal(ref.unwrapped(p.positions), pos)
    t = granule_table(p, fast.labels, 1.0, fast.unwrapped_axis, 1, 0.0, L, fast.percolating)
    assert t["percolating"].tolist() == [True, False]
    assert t.loc[0, "com_y"] == pytest.approx(y[:4].mean())
    # an open chain over the same positions does not percolate
    _, ref, fast = _all_bonded(pos, [0, 1, 2], [1, 2, 3], L)
    assert not fast.percolating.any() and not ref.percolating.any()


@st.composite
def graphs(draw):
    n = draw(st.integers(1, 60))
    m = draw(st.integers(0, 2 * n))
    a = draw(st.lists(st.integers(0, n - 1), min_size=m, max_size=m))
    b = draw(st.lists(st.integers(0, n - 1), min_size=m, max_size=m))
    pairs = sorted({(min(x, y), max(x, y)) for x, y in zip(a, b) if x != y})
    i = np.array([x for x, _ in pairs], dtype=np.int64)
    j = np.array([y for _, y in pairs], dtype=np.int64)
    perm = draw(st.permutations(range(len(pairs))))
    return n, i[list(perm)], j[list(perm)]


@settings(max_examples=200, deadline=None)
@given(graphs())
def test_reference_equals_fast_on_random_graphs(g):
    n, i, j = g
    ref, fast = label_reference(n, i, j), label_fast(n, i, j)
    np.testing.assert_array_equal(ref, fast)
    # a partition into connected components: bonded pairs share a label, and there are as
    # many labels as networkx counts components; canonical numbering by first member
    assert np.all(fast[i] == fast[j])
    graph = nx.Graph()
    graph.add_nodes_from(range(n))
    graph.add_edges_from(zip(i.tolist(), j.tolist()))
    assert fast.max() + 1 == nx.number_connected_components(graph)
    assert np.all(np.unique(fast, return_index=True)[1] == np.sort(np.unique(fast, return_index=True)[1]))


@settings(max_examples=150, deadline=None)
@given(graphs(), st.integers(0, 2**31 - 1))
def test_fused_pass_equals_reference_on_random_graphs(g, seed):
    """Union-find with image counts == networkx BFS unwrap: labels, percolating granules
    (random positions make many cycles around the axis) and the layout of the others."""
    n, i, j = g
    L = 0.02
    rng = np.random.default_rng(seed)
    pos = rng.uniform(0, L, size=(n, 3))
    p, ref, fast = _all_bonded(pos, i, j, L)
    _same_identification(p, ref, fast, atol=1e-12 * L)
    np.testing.assert_array_equal(fast.labels, label_reference(n, i, j))


def test_unwrap_chain_across_boundary():
    """A chain of bonded particles crossing y = L is laid out continuously."""
    L = 0.01
    y = np.array([0.8, 0.9, 0.0, 0.1, 0.2]) * L          # 0.8 -> 1.2 unwrapped
    pos = np.column_stack([np.zeros(5), y, np.zeros(5)])
    _, ref, fast = _all_bonded(pos, [3, 0, 2, 1], [4, 1, 3, 2], L)
    np.testing.assert_allclose(fast.unwrapped_axis, np.array([0.8, 0.9, 1.0, 1.1, 1.2]) * L)
    np.testing.assert_allclose(ref.unwrapped_axis, fast.unwrapped_axis, atol=1e-15)


@settings(max_examples=30, deadline=None)
@given(graphs(), st.integers(0, 1000))
def test_louvain_refines_components(g, seed):
    n, i, j = g
    force = np.random.default_rng(seed).uniform(0.1, 1.0, len(i))
    comm = louvain_labels(n, i, j, force, seed=seed)
    comp = label_fast(n, i, j)
    # every community lies inside one connected component
    for k in np.unique(comm):
        assert len(np.unique(comp[comm == k])) == 1
