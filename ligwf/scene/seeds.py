"""Random seeds of a case: the primes LIGGGHTS needs for each random stream of a replica.

LIGGGHTS requires seeds that are primes above 10000 and fit its 32-bit int; each replica of
a study gets its own distinct streams (particle templates, the size distribution, each
insertion wave), derived from the scene's base seed.
"""

from __future__ import annotations

from ligwf.errors import ConfigError

#: LIGGGHTS reads seeds as 32-bit ints
INT_MAX = 2**31 - 1


def is_prime(n: int) -> bool:
    if n < 2:
        return False
    if n % 2 == 0:
        return n == 2
    k = 3
    while k * k <= n:
        if n % k == 0:
            return False
        k += 2
    return True


def next_prime(n: int) -> int:
    """Smallest prime >= n."""
    while not is_prime(n):
        n += 1
    return n


def replica_seeds(base: int, replica: int, count: int = 3) -> tuple[int, ...]:
    """Distinct primes > 10000 (LIGGGHTS requires them) for one replica's random streams;
    each must fit the engine's 32-bit int, else ConfigError naming the base seed."""
    seeds: list[int] = []
    p = max(base, 10007) + 10007 * replica
    for _ in range(count):
        p = next_prime(p + 1 if seeds else p)
        seeds.append(p)
    if seeds and seeds[-1] > INT_MAX:
        raise ConfigError(f"scene.numerics.seed = {base}: replica {replica}'s random streams "
                          f"reach {seeds[-1]} > {INT_MAX} (the engine's largest int); allowed "
                          f"range [10000, {INT_MAX - 10007 * (replica + 1)}] for this study")
    return tuple(seeds)
