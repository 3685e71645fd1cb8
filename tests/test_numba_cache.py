"""Compiled kernels are cached across processes (ligwf.numba_cache, the *_numba modules).

A second process (a second ``ligwf analyse``, another MPI rank) must load every kernel,
the liquid-law bond kernels included, from numba's cache instead of compiling it again,
and compute the same bits as the process that compiled it. The cache must also work in a
read-only install whose user has no writable cache folder.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from helpers import ROOT
from ligwf import liquids
from ligwf.analysis import granules_numba as gn

# One "analyse-like" process: every kernel started (compiled or loaded), then the bond
# kernels of each wet law on a frame; prints the start time, numba's cache statistics of
# every kernel and a digest of the results.
_PROCESS = textwrap.dedent("""
    import hashlib, json, sys, time
    import numpy as np
    from ligwf import liquids
    from ligwf.analysis import cpm_numba, dumps_numba, granules_numba as gn

    models = sys.argv[1].split(",")
    t0 = time.perf_counter()
    if sys.argv[2] == "all":
        gn.warm_up(tuple(models))
        dumps_numba.warm_up()
    start = time.perf_counter() - t0

    rng = np.random.default_rng(7)
    n, m = 400, 1500
    radii = rng.uniform(0.5e-3, 1.5e-3, n)
    content = rng.uniform(0.005, 0.03, n)
    vel = rng.normal(size=(n, 3))
    id1, id2 = rng.integers(1, n + 1, m), rng.integers(1, n + 1, m)
    delta = rng.uniform(-2e-4, 5e-5, m)            # overlaps and gaps (delta = -gap)
    y = rng.uniform(0.0, 0.009, n)
    h = hashlib.sha256()
    for name in models:
        law = gn.law(liquids.get(name))
        for angle in (-1.0, 0.5):
            count, i, j, f, rows = gn.bond_kernel(id1, id2, 1, vel, radii, content, delta,
                                                  *law, 0.05, 0.4, angle, 0.0)
            c2, i2, j2, f2, labels, unwrapped, perc, _ = gn.bond_components(
                id1, id2, 1, vel, radii, content, delta, *law, 0.05, 0.4, angle, 0.0, True,
                y, 0.009)
            lo, hi = np.zeros(count), np.full(count, 1e-4)
            work = gn.rupture_work(radii[i[:count]], radii[j[:count]], lo, hi,
                                   np.full(count, 1e-11), law[2], 0.05, 0.4,
                                   *np.polynomial.legendre.leggauss(8))
            if sys.argv[2] != "all" and angle < 0.0:
                start = time.perf_counter() - t0      # the first call compiled or loaded them
            for a in (i[:count], j[:count], f[:count], rows[:count], i2[:c2], j2[:c2],
                      f2[:c2], labels, unwrapped, perc, work):
                h.update(np.ascontiguousarray(a).tobytes())
    # every kernel entered from Python (those only called by other kernels are inside them)
    kernels = list(gn._COMPILED.values()) + [
        d for mod in (gn, cpm_numba, dumps_numba) for d in vars(mod).values()
        if hasattr(d, "stats")]
    stats = sorted((d.py_func.__qualname__, sum(d.stats.cache_hits.values()),
                    sum(d.stats.cache_misses.values())) for d in kernels)
    stats = [s for s in stats if s[1] + s[2]]
    print(json.dumps({"start": start, "stats": stats, "digest": h.hexdigest()}))
""")


def _run(env: dict, code: str = _PROCESS, cwd: Path = ROOT, args: tuple = ()) -> dict:
    proc = subprocess.run([sys.executable, "-c", code, *args], cwd=cwd, env=env, text=True,
                          capture_output=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _first_and_second(tmp_path, models: tuple[str, ...], which: str) -> tuple[dict, dict]:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    args = (",".join(models), which)
    first = _run(env, args=args)
    second = _run(env, args=args)
    names = [s[0] for s in first["stats"]]
    # the liquid-law kernels are among them, one per wet model
    for kernel in ("_bond_kernel", "_bond_components", "_rupture_work"):
        for model in models:
            assert any(q.startswith(f"{kernel}__{model}_") for q in names), (kernel, model)
    assert all(misses >= 1 for _, _, misses in first["stats"]), first["stats"]
    # second process: every kernel it enters is a cache hit, nothing compiled (the first
    # also lists the helpers it compiled inside them)
    loaded = [s[0] for s in second["stats"]]
    assert set(loaded) <= set(names)
    assert all(q in loaded for q in names if q.startswith(("_bond_", "_rupture_work__")))
    assert all(hits >= 1 and misses == 0 for _, hits, misses in second["stats"]), \
        second["stats"]
    print(f"kernel start: first process {first['start']:.2f} s (compiled), second "
          f"{second['start']:.3f} s (loaded), {len(names)} kernels")
    assert second["start"] < first["start"] / 5, (first["start"], second["start"])
    assert second["digest"] == first["digest"]           # loaded code, the same bits
    assert any((tmp_path / "numba").rglob(f"granules_numba._bond_components__{models[0]}_*.nbc"))
    return first, second


@pytest.mark.slow
def test_second_process_loads_the_bond_kernels_from_the_cache(tmp_path):
    """The kernels that take a liquid law (the ones that recompiled in every process)."""
    _first_and_second(tmp_path, ("washino",), "law")


@pytest.mark.slow
def test_second_process_loads_every_kernel_from_the_cache(tmp_path):
    """Every kernel of an analysis (bond kernels of both wet laws, union-find, Louvain,
    granule sums, the dump decoders): ~20 compilations, 15-60 s."""
    _first_and_second(tmp_path, ("easo", "washino"), "all")


def test_a_changed_law_is_compiled_again_not_loaded(tmp_path):
    """The law's source file is part of the kernel's cache name: numba alone would load a
    kernel with the old law inlined (it checks only the kernel's own file)."""
    from ligwf.numba_cache import law_digest

    law = tmp_path / "law.py"
    law.write_text("def force(x):\n    return 2.0 * x\n")
    ns: dict = {}
    exec(compile(law.read_text(), str(law), "exec"), ns)
    before = law_digest(ns["force"])
    law.write_text("def force(x):\n    return 2.0 * x\n\nFACTOR = 3.0\n")
    assert law_digest(ns["force"]) != before
    law.write_text("def force(x):\n    return 2.0 * x\n")
    assert law_digest(ns["force"]) == before


_KERNEL_MODULE = textwrap.dedent("""
    from ligwf.numba_cache import cached_jit

    @cached_jit()
    def twice(x):
        return 2 * x
""")


@pytest.mark.parametrize("with_ligwf", [True, False])
def test_read_only_install_without_a_user_cache(tmp_path, with_ligwf):
    """The kernel's folder cannot hold ``__pycache__`` and the user's cache folder cannot
    be made: plain numba refuses at import; ligwf's kernels fall back to a private folder
    in the temporary directory, compiled by the first process, loaded by the second."""
    pkg = tmp_path / "site"
    pkg.mkdir()
    (pkg / "__pycache__").write_text("a file, so no cache folder here")
    source = _KERNEL_MODULE if with_ligwf else _KERNEL_MODULE.replace(
        "from ligwf.numba_cache import cached_jit", "from numba import njit").replace(
        "@cached_jit()", "@njit(cache=True)")
    (pkg / "kern.py").write_text(source)
    blocker = tmp_path / "blocker"
    blocker.write_text("")
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(XDG_CACHE_HOME=str(blocker / "cache"), TMPDIR=str(tmpdir),
               PYTHONPATH=str(pkg), PYTHONDONTWRITEBYTECODE="1")
    code = ("import json, kern; kern.twice(21); s = kern.twice.stats; "
            "print(json.dumps([sum(s.cache_hits.values()), sum(s.cache_misses.values())]))")
    if not with_ligwf:
        proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, text=True,
                              capture_output=True, timeout=300)
        assert proc.returncode != 0 and "no locator available" in proc.stderr
        return
    assert _run(env, code, tmp_path) == [0, 1]
    assert _run(env, code, tmp_path) == [1, 0]
    assert list(tmpdir.glob(f"ligwf-numba-cache-{os.getuid()}/*/kern.twice-*.nbi"))


# -- the cached law kernels compute what the law-as-argument kernels computed ---------------

@njit(error_model="numpy")
def _bond_kernel_law_arguments(id1, id2, id_offset, velocities, radii, content, delta, volume,
                               within_rupture, force, gamma, theta, cos_max, min_force,
                               force_needed):
    """The bond pass as it was compiled before the law kernels were cached: the law's
    functions as arguments of the kernel (one uncached compilation per process)."""
    m = len(id1)
    out_i = np.empty(m, np.int64)
    out_j = np.empty(m, np.int64)
    out_f = np.empty(m, np.float64)
    out_k = np.empty(m, np.int64)
    count = gn._scan(volume, within_rupture, force, id1, id2, id_offset, velocities, radii,
                     content, delta, gamma, theta, cos_max, min_force, force_needed, out_i,
                     out_j, out_f, out_k)
    return count, out_i, out_j, out_f, out_k


@njit(error_model="numpy")
def _rupture_work_law_argument(r_i, r_j, lo, hi, vol, force, gamma, theta, nodes, weights):
    cos_theta, sin_theta = math.cos(theta), math.sin(theta)
    out = np.empty(len(r_i), np.float64)
    for k in range(len(r_i)):
        half, mid = 0.5 * (hi[k] - lo[k]), 0.5 * (hi[k] + lo[k])
        total = 0.0
        for q in range(len(nodes)):
            total += weights[q] * force(r_i[k], r_j[k], mid + half * nodes[q], gamma, theta,
                                        cos_theta, sin_theta, vol[k])
        out[k] = half * total
    return out


@pytest.mark.mpi
def test_cached_law_kernels_equal_the_law_argument_kernels_bitwise_on_real_dumps(
        engine, tmp_path_factory):
    """Every frame of the real wet run (tests/wetdump.py), both capillary laws, with and
    without the velocity-angle test: the same bonds, forces, granules, unwrapped
    coordinates and rupture work, to the bit."""
    from ligwf.analysis.frames.dumps import discover_frames, read_contacts, read_particles
    from wetdump import wet_study

    case = wet_study(engine, tmp_path_factory) / "cg3-weber-r0"
    scaled = json.loads((case / "scene.json").read_text())["scaled"]
    length = float(scaled["drum_length"])
    nodes, weights = np.polynomial.legendre.leggauss(8)
    frames = [(read_particles(f.particles), read_contacts(f.contacts))
              for f in discover_frames(case)]
    assert frames
    for name in ("washino", "easo"):
        law = gn.law(liquids.get(name))
        for p, c in frames:
            a, b = p.index_of(c.id1), p.index_of(c.id2)
            content = np.asarray(p.liquid_content, dtype=np.float64)
            y = np.ascontiguousarray(p.positions[:, 1])
            delta = np.asarray(c.delta, dtype=np.float64)
            for cos_max in (-1.0, math.cos(math.radians(30.0))):
                args = (a, b, 0, p.velocities, p.radii, content, delta)
                crit = (0.02, 0.3, cos_max, 0.0)
                new = gn.bond_kernel(*args, *law, *crit)
                old = _bond_kernel_law_arguments(*args, *law, *crit, True)
                count = new[0]
                assert count == old[0] and count > 0
                for x, z in zip(new[1:], old[1:]):
                    assert x[:count].tobytes() == z[:count].tobytes()
                comp = gn.bond_components(*args, *law, *crit, True, y, length)
                assert comp[0] == count
                for x, z in zip(comp[1:4], new[1:4]):
                    assert x[:count].tobytes() == z[:count].tobytes()
                labels, unwrapped, perc, n = gn.components_images(len(p), old[1], old[2],
                                                                   count, y, length)
                assert comp[4].tobytes() == labels.tobytes()
                assert comp[5].tobytes() == unwrapped.tobytes() and comp[7] == n
                i, j = new[1][:count], new[2][:count]
                lo, hi = np.zeros(count), np.full(count, 1e-5)
                vol = np.full(count, 1e-12)
                w_new = gn.rupture_work(p.radii[i], p.radii[j], lo, hi, vol, law[2], 0.02,
                                        0.3, nodes, weights)
                w_old = _rupture_work_law_argument(p.radii[i], p.radii[j], lo, hi, vol,
                                                   law[2], 0.02, 0.3, nodes, weights)
                assert w_new.tobytes() == w_old.tobytes()
