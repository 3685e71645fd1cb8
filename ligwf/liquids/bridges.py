"""Liquid-bridge force laws of LIGGGHTS 3.8.0, evaluated in Python (numpy, vectorised).

These mirror ``cohesion_model_washino_capillary_viscous.h`` and
``cohesion_model_easo_capillary_viscous.h`` so ligwf can (a) prove its CG scaling on the
formulas themselves, (b) compare the engine's measured pair force with the published law,
and (c) evaluate bridge forces of dumped contacts during granule analysis.

Conventions: SI units, forces returned as positive magnitudes of attraction (the engine
applies them as negative normal forces), ``gap`` is the surface separation
``|x_i - x_j| - (r_i + r_j)`` (negative when the spheres overlap).

Engine quirk handled here: both models compute the effective contact angle as
``0.5 * theta_i * theta_j`` (radians) instead of the mean. For a single particle type with
input angle ``theta_in`` the engine therefore applies ``0.5 * theta_in**2``; passing
``theta_in = sqrt(2 theta)`` makes it apply ``theta`` (see :func:`engine_contact_angle_deg`).
"""

from __future__ import annotations

import math

import numpy as np

#: LIGGGHTS' default fraction of the two particles' liquid that forms a washino bridge
#: (``lbVolumeFraction``, used unless ``modifyLbVolume`` is switched on).
WASHINO_BRIDGE_VOLUME_FRACTION = 0.05


def engine_contact_angle_deg(theta_deg: float, compensate: bool = True) -> float:
    """Contact angle to write into the LIGGGHTS input so the engine applies ``theta_deg``.

    LIGGGHTS 3.8.0 applies ``0.5 * a * a`` (radians) for an input angle ``a`` on both
    partners. Solving ``0.5 a^2 = theta`` gives ``a = sqrt(2 theta)``, which stays within the
    engine's accepted [0, 180] deg for every theta in [0, 180] deg. With ``compensate=False``
    (an engine with the upstream fix) the angle is passed through.
    """
    if not compensate:
        return theta_deg
    return math.degrees(math.sqrt(2.0 * math.radians(theta_deg)))


def engine_effective_angle_rad(theta_in_deg_i: float, theta_in_deg_j: float | None = None,
                               product_bug: bool = True) -> float:
    """Effective angle (radians) the engine applies for input angles of two partners."""
    a = math.radians(theta_in_deg_i)
    b = math.radians(theta_in_deg_j if theta_in_deg_j is not None else theta_in_deg_i)
    return 0.5 * a * b if product_bug else 0.5 * (a + b)


def sphere_volume(r):
    """4/3 pi r^3, m^3, with r^3 as r*r*r: twice as fast as numpy's pow, and the compiled
    granule kernels evaluate the same expression, so bridge volumes agree to the last bit."""
    r = np.asarray(r, dtype=float)
    return 4.0 / 3.0 * np.pi * (r * r * r)


def washino_bridge_volume(r_i, r_j, content_i, content_j,
                          fraction: float = WASHINO_BRIDGE_VOLUME_FRACTION):
    """Bridge volume, m^3: ``fraction`` of both particles' surface liquid."""
    return fraction * (sphere_volume(r_i) * content_i + sphere_volume(r_j) * content_j)


def easo_bridge_volume(r_i, r_j, content_i, content_j):
    """Bridge volume, m^3: each partner gives the liquid on its spherical cap facing the other."""
    r_i, r_j = np.asarray(r_i, float), np.asarray(r_j, float)
    s = r_i + r_j
    cap_i = 0.5 * (1.0 - np.sqrt(1.0 - r_j**2 / s**2))
    cap_j = 0.5 * (1.0 - np.sqrt(1.0 - r_i**2 / s**2))
    return sphere_volume(r_i) * content_i * cap_i + sphere_volume(r_j) * content_j * cap_j


def rupture_distance(bridge_volume, theta_rad):
    """Gap at which a bridge breaks, m: (1 + theta/2) V^(1/3) (Lian et al., both models)."""
    return (1.0 + 0.5 * theta_rad) * np.cbrt(bridge_volume)


def washino_capillary_force(r_i, r_j, gap, surface_tension, theta_rad, content_i, content_j):
    """Capillary force magnitude of the washino model, N (0 beyond rupture).

    Touching (gap <= 0): F = 2 pi R* gamma cos(theta) (1 - gap sqrt(pi R* / (2 V)))
    (Rabinovich et al., Langmuir 21 (2005), eq. A11, as coded in LIGGGHTS).
    Separated (0 < gap < rupture): with p = -1 + sqrt(1 + 2 V / (pi R* gap^2)),
    d_sp = gap p / 2, alpha = sqrt(gap p / R*):
    F = 2 pi R* gamma (cos(theta) / (1 + gap / (2 d_sp)) + sin(alpha) sin(alpha + theta))
    (Rabinovich et al. eqs. 19, 20, A3). R* = r_i r_j / (r_i + r_j).
    """
    r_i, r_j, gap = (np.asarray(a, float) for a in (r_i, r_j, gap))
    r_eff = r_i * r_j / (r_i + r_j)
    vol = washino_bridge_volume(r_i, r_j, content_i, content_j)
    with np.errstate(divide="ignore", invalid="ignore"):
        touching = 2 * np.pi * r_eff * surface_tension * np.cos(theta_rad) * (
            1.0 - gap * np.sqrt(np.pi * r_eff / (2.0 * vol)))
        p = -1.0 + np.sqrt(1.0 + 2.0 * vol / (np.pi * r_eff * gap**2))
        d_sp = 0.5 * gap * p
        alpha = np.sqrt(gap / r_eff * p)
        separated = 2 * np.pi * r_eff * surface_tension * (
            np.cos(theta_rad) / (1.0 + gap / (2.0 * d_sp)) + np.sin(alpha) * np.sin(alpha + theta_rad))
    out = np.where(gap <= 0.0, touching, separated)
    out = np.where(gap < rupture_distance(vol, theta_rad), out, 0.0)
    return out if out.ndim else float(out)


def easo_capillary_force(r_i, r_j, gap, surface_tension, theta_rad, content_i, content_j):
    """Capillary force magnitude of the easo model, N (0 beyond rupture).

    Soulie et al., Int. J. Numer. Anal. Meth. Geomech. 30 (2006) eqs. 13-14, as coded in
    LIGGGHTS: with R2 = max(r_i, r_j) and V* = V / R2^3,
    F = pi gamma sqrt(r_i r_j) (exp(A gap / R2 + B) + C),
    A = -1.1 V*^-0.53, B = (-0.148 ln V* - 0.96) theta^2 - 0.0082 ln V* + 0.48,
    C = 0.0018 ln V* + 0.078; the gap term is dropped while the spheres touch.
    """
    r_i, r_j, gap = (np.asarray(a, float) for a in (r_i, r_j, gap))
    vol = easo_bridge_volume(r_i, r_j, content_i, content_j)
    r2 = np.maximum(r_i, r_j)
    vs = vol / r2**3
    a = -1.1 * vs ** (-0.53)
    b = (-0.148 * np.log(vs) - 0.96) * theta_rad**2 - 0.0082 * np.log(vs) + 0.48
    c = 0.0018 * np.log(vs) + 0.078
    expo = np.where(gap > 0.0, a * gap / r2 + b, b)
    out = np.pi * surface_tension * np.sqrt(r_i * r_j) * (np.exp(expo) + c)
    out = np.where(gap < rupture_distance(vol, theta_rad), out, 0.0)
    return out if out.ndim else float(out)


def capillary_force(model: str, r_i, r_j, gap, surface_tension, theta_rad, content_i,
                    content_j=None):
    """Dispatch to the named model's capillary force (``washino`` or ``easo``)."""
    if content_j is None:
        content_j = content_i
    if model == "washino":
        return washino_capillary_force(r_i, r_j, gap, surface_tension, theta_rad, content_i, content_j)
    if model == "easo":
        return easo_capillary_force(r_i, r_j, gap, surface_tension, theta_rad, content_i, content_j)
    raise ValueError(f"no capillary force law for liquid model {model!r}")


def bridge_volume(model: str, r_i, r_j, content_i, content_j=None):
    """Bridge volume of the named model, m^3."""
    if content_j is None:
        content_j = content_i
    if model == "washino":
        return washino_bridge_volume(r_i, r_j, content_i, content_j)
    if model == "easo":
        return easo_bridge_volume(r_i, r_j, content_i, content_j)
    raise ValueError(f"no bridge volume for liquid model {model!r}")


def viscous_normal_force(r_i, r_j, gap, viscosity, normal_speed, min_separation_ratio):
    """Normal lubrication force magnitude, N: 6 pi mu R* v_n / max(s_min, gap / R*)
    (Nase et al. as cited by Shi and McCarthy, Powder Technol. 184 (2008) eq. 40)."""
    r_i, r_j, gap = (np.asarray(a, float) for a in (r_i, r_j, gap))
    r_eff = r_i * r_j / (r_i + r_j)
    out = 6 * np.pi * viscosity * r_eff * np.abs(normal_speed) / np.maximum(
        min_separation_ratio, gap / r_eff)
    return out if out.ndim else float(out)
